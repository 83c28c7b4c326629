package io.github.sitar;

/**
 * The JNI entry point of libsitar.so that the Unity package calls on Android
 * (SitarPlatformTls.Init in Runtime/SitarSession.cs, through AndroidJavaClass). The Kotlin
 * library declares the same class (android/.../Native.kt, generated); a Unity app does not
 * include that one. Unity compiles this file into Android players' Gradle build. Errors
 * arrive as SitarException (SitarException.java).
 */
public final class Native {
    static {
        System.loadLibrary("sitar");
    }

    private Native() {}

    /**
     * Unpinned https uses Android's trust store and policy (rustls-platform-verifier) from
     * now on; true when it does. Needs the verifier's AAR in the app (README.md, "HTTPS").
     */
    public static native boolean platformTlsInit(Object context);
}
