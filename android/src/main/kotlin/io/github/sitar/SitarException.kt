package io.github.sitar

/**
 * An error reported by the native library. [code] is the C ABI status (`SITAR_ERR_*`),
 * [status] the same as a [SitarStatus] (generated from the library's declarations); the
 * message says what is wrong. Thrown from native code through the `(int, String)`
 * constructor (kept by the consumer ProGuard rules).
 */
class SitarException(val code: Int, message: String) : RuntimeException(message) {
    /** The status, or null for a code this wrapper does not know. */
    val status: SitarStatus? get() = SitarStatus.of(code)
}
