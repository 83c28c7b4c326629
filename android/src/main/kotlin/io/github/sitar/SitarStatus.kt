// Generated from rust/ffi/src (c_enum!) by rust/ffi/tests/generated_bindings.rs; do not edit.
// Regenerate: SITAR_REGENERATE=1 cargo test -p sitar-ffi --test generated_bindings
package io.github.sitar

/**
 * Status codes of every C ABI function (`int32_t`); negative is an error.
 *
 * JNI reports the same codes as `SitarException.code`.
 */
enum class SitarStatus(val code: Int) {
    /** Success. */
    OK(0),
    /** A required pointer argument was NULL. */
    NULL(-1),
    /** An argument is out of range, malformed or not valid UTF-8. */
    INVALID_ARGUMENT(-2),
    /** A NULL, stale, freed or garbage handle, or a handle of another kind. */
    INVALID_HANDLE(-3),
    /** The call is not valid in the object's current state. */
    INVALID_STATE(-4),
    /** Text (JSON config, results CSV/JSON) could not be parsed. */
    PARSE(-5),
    /** A file could not be read or written. */
    IO(-6),
    /** The backend could not be reached or answered with an error. */
    NETWORK(-7),
    /** An output buffer is too small; the needed length was written to `*out_len`. */
    BUFFER_TOO_SMALL(-8),
    /** A panic inside the library was caught (a bug; please report it). */
    PANIC(-99);

    companion object {
        /** The constant with this code, or null for a code this library does not know. */
        @JvmStatic fun of(code: Int): SitarStatus? = values().firstOrNull { it.code == code }
    }
}

/** States of a background upload job (`SitarJobProgress.state`). */
enum class UploadState(val code: Int) {
    /** Creating the server session. */
    STARTING(0),
    /** Sending the recording. */
    UPLOADING(1),
    /** Playback trials running on the server. */
    PLAYING(2),
    /** The server computes the final estimate. */
    ESTIMATING(3),
    /** Fetching the final results. */
    DOWNLOADING(4),
    /** Final results are loaded into the session. */
    DONE(5),
    /** Failed: see `error_code` and `sitar_upload_message`. */
    FAILED(6),
    /** Cancelled by `sitar_upload_cancel`. */
    CANCELLED(7);

    companion object {
        /** The constant with this code, or null for a code this library does not know. */
        @JvmStatic fun of(code: Int): UploadState? = values().firstOrNull { it.code == code }
    }
}
