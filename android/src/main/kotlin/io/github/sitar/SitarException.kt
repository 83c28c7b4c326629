package io.github.sitar

/**
 * An error reported by the native library. [code] is the C ABI status
 * (`SITAR_ERR_*`, see the constants); the message says what is wrong.
 * Thrown from native code through the `(int, String)` constructor (kept by
 * the consumer ProGuard rules).
 */
class SitarException(val code: Int, message: String) : RuntimeException(message) {
    companion object {
        const val NULL = -1
        const val INVALID_ARGUMENT = -2
        const val INVALID_HANDLE = -3
        const val INVALID_STATE = -4
        const val PARSE = -5
        const val IO = -6
        const val NETWORK = -7
        const val BUFFER_TOO_SMALL = -8
        const val PANIC = -99
    }
}
