// Stubs of the UnityEditor API (Unity 2021.3) used by unity-plugin/Editor, for
// the type-check in tests/tests/unity_meta.rs (compiled together with
// ../unity_stubs). Real names, namespaces and signatures; nothing runs.
using System;

namespace UnityEditor
{
    public enum BuildTarget
    {
        StandaloneOSX = 2,
        StandaloneWindows = 5,
        iOS = 9,
        Android = 13,
        StandaloneWindows64 = 19,
        StandaloneLinux64 = 24,
    }

    public sealed class PlayerSettings : UnityEngine.Object
    {
        public static class Android
        {
            public static bool forceInternetPermission { get { throw null; } set { throw null; } }
        }
    }

    [AttributeUsage(AttributeTargets.Method, AllowMultiple = true)]
    public sealed class MenuItem : Attribute
    {
        public MenuItem(string itemName) { throw null; }
    }

    [AttributeUsage(AttributeTargets.Class)]
    public class InitializeOnLoadAttribute : Attribute { }
}

namespace UnityEditor.Build
{
    public interface IOrderedCallback
    {
        int callbackOrder { get; }
    }

    public interface IPreprocessBuildWithReport : IOrderedCallback
    {
        void OnPreprocessBuild(UnityEditor.Build.Reporting.BuildReport report);
    }
}

namespace UnityEditor.Build.Reporting
{
    public sealed class BuildReport : UnityEngine.Object
    {
        public BuildSummary summary { get { throw null; } }
    }

    public struct BuildSummary
    {
        public UnityEditor.BuildTarget platform { get { throw null; } }
    }
}
