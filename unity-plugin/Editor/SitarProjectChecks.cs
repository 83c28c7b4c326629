// Editor side of the package: what a project needs that code cannot ask for at
// run time.
// - Internet Access: Require. Unity's "Auto" adds Android's INTERNET permission
//   only when it sees UnityWebRequest in C#; libsitar uploads over its own
//   sockets, which Unity cannot see, so every Android build gets "Require".
// - The desktop library for Play Mode: on a Linux Editor, without
//   Plugins/Linux/x86_64/libsitar.so the first call is a DllNotFoundException;
//   say at load time what to run instead.
using System.IO;
using UnityEditor;
using UnityEditor.Build;
using UnityEditor.Build.Reporting;
using UnityEngine;

namespace Sitar.Editor
{
    /// <summary>Sets Player Settings → Android → Internet Access to Require before every Android build.</summary>
    sealed class SitarAndroidInternetAccess : IPreprocessBuildWithReport
    {
        public int callbackOrder { get { return 0; } }

        public void OnPreprocessBuild(BuildReport report)
        {
            if (report.summary.platform == BuildTarget.Android) Require();
        }

        [MenuItem("Tools/SiTAR/Set Android Internet Access to Require")]
        static void Require()
        {
            if (PlayerSettings.Android.forceInternetPermission) return;
            PlayerSettings.Android.forceInternetPermission = true;
            Debug.Log("SiTAR: Player Settings → Android → Internet Access is now Require: libsitar uploads over its own sockets, which \"Auto\" does not see.");
        }
    }

    /// <summary>Warns once per Editor load when Play Mode would miss the native library.</summary>
    [InitializeOnLoad]
    static class SitarEditorLibraryCheck
    {
        /// <summary>Where scripts/build-unity-plugins puts the Linux x86_64 library.</summary>
        public const string LinuxLibrary = "Packages/io.github.sitar/Plugins/Linux/x86_64/libsitar.so";

        static SitarEditorLibraryCheck()
        {
#if UNITY_EDITOR_LINUX
            if (!File.Exists(Path.GetFullPath(LinuxLibrary)))
            {
                Debug.LogWarning("SiTAR: " + LinuxLibrary + " is missing, so Play Mode cannot load libsitar. Run scripts/build-unity-plugins in the SiTAR repository (docs/src/ar/unity.md, step 1).");
            }
#elif UNITY_EDITOR_WIN || UNITY_EDITOR_OSX
            Debug.Log("SiTAR: Play Mode needs libsitar for this desktop, which the package has only for Linux x86_64; test on the phone, or build sitar-ffi for this OS into Plugins/ (docs/src/ar/unity.md).");
#endif
        }
    }
}
