// Generated from rust/ffi/src (c_enum!) by rust/ffi/tests/generated_bindings.rs; do not edit.
// Regenerate: SITAR_REGENERATE=1 cargo test -p sitar-ffi --test generated_bindings
namespace Sitar
{
    /// <summary>
    /// Status codes of every C ABI function (`int32_t`); negative is an error.
    ///
    /// JNI reports the same codes as `SitarException.code`.
    /// </summary>
    public enum SitarErrorCode
    {
        /// <summary>Success.</summary>
        Ok = 0,
        /// <summary>A required pointer argument was NULL.</summary>
        Null = -1,
        /// <summary>An argument is out of range, malformed or not valid UTF-8.</summary>
        InvalidArgument = -2,
        /// <summary>A NULL, stale, freed or garbage handle, or a handle of another kind.</summary>
        InvalidHandle = -3,
        /// <summary>The call is not valid in the object's current state.</summary>
        InvalidState = -4,
        /// <summary>Text (JSON config, results CSV/JSON) could not be parsed.</summary>
        Parse = -5,
        /// <summary>A file could not be read or written.</summary>
        Io = -6,
        /// <summary>The backend could not be reached or answered with an error.</summary>
        Network = -7,
        /// <summary>An output buffer is too small; the needed length was written to `*out_len`.</summary>
        BufferTooSmall = -8,
        /// <summary>A panic inside the library was caught (a bug; please report it).</summary>
        Panic = -99,
    }

    /// <summary>
    /// States of a background upload job (`SitarJobProgress.state`).
    /// </summary>
    public enum UploadState
    {
        /// <summary>Creating the server session.</summary>
        Starting = 0,
        /// <summary>Sending the recording.</summary>
        Uploading = 1,
        /// <summary>Playback trials running on the server.</summary>
        Playing = 2,
        /// <summary>The server computes the final estimate.</summary>
        Estimating = 3,
        /// <summary>Fetching the final results.</summary>
        Downloading = 4,
        /// <summary>Final results are loaded into the session.</summary>
        Done = 5,
        /// <summary>Failed: see `error_code` and `sitar_upload_message`.</summary>
        Failed = 6,
        /// <summary>Cancelled by `sitar_upload_cancel`.</summary>
        Cancelled = 7,
    }
}
