// Which certificates an unpinned https:// server is checked against on Android.

#if UNITY_ANDROID && !UNITY_EDITOR
using System;
using UnityEngine;
#endif

namespace Sitar
{
    /// <summary>
    /// Lets unpinned https:// uploads (no server_cert_sha256) trust what Android trusts: the
    /// device's trust store and Android's policy (rustls-platform-verifier). Call
    /// <see cref="Init"/> once before the first upload (SitarRecorder does); later calls
    /// return the first answer. Without it, or without the verifier's AAR in the app
    /// (README.md, "HTTPS"), the library checks servers against the Mozilla roots bundled in
    /// it: a public certificate works, a site CA does not (pin it), and logcat says why.
    /// Elsewhere (the Editor, desktop players) the platform's verifier is always in use.
    /// </summary>
    public static class SitarPlatformTls
    {
        static readonly object Gate = new object();
        static bool? initialised;

        /// <summary>True when the platform's verifier checks unpinned https from now on.</summary>
        public static bool Init()
        {
            lock (Gate)
            {
                if (!initialised.HasValue) initialised = InitOnce();
                return initialised.Value;
            }
        }

#if UNITY_ANDROID && !UNITY_EDITOR
        // The library's JNI entry point (Plugins/Android/Native.java) with the application
        // Context: the verifier keeps it, and its class loader finds the AAR's classes.
        static bool InitOnce()
        {
            try
            {
                using (var player = new AndroidJavaClass("com.unity3d.player.UnityPlayer"))
                using (var activity = player.GetStatic<AndroidJavaObject>("currentActivity"))
                using (var context = activity.Call<AndroidJavaObject>("getApplicationContext"))
                using (var native = new AndroidJavaClass("io.github.sitar.Native"))
                {
                    return native.CallStatic<bool>("platformTlsInit", context);
                }
            }
            catch (Exception e)
            {
                Debug.LogWarning("SiTAR: unpinned https keeps the bundled roots: " + e.Message);
                return false;
            }
        }
#else
        static bool InitOnce()
        {
            return true;
        }
#endif
    }
}
