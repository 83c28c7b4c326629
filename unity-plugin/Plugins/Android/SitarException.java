package io.github.sitar;

/**
 * What libsitar.so throws from a JNI entry point (Native.java) on error: the C ABI status
 * code (SitarErrorCode) and the message. The Kotlin library declares the same class; a
 * Unity app does not include that one. C# sees it as an AndroidJavaException.
 */
public class SitarException extends RuntimeException {
    private final int code;

    public SitarException(int code, String message) {
        super(message);
        this.code = code;
    }

    /** The status code (SitarErrorCode). */
    public int getCode() {
        return code;
    }
}
