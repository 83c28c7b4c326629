// Stubs of the ARCore XR Plugin API (com.unity.xr.arcore 5.1, assembly
// Unity.XR.ARCore) used by unity-plugin/Runtime under UNITY_ANDROID. They
// exist only to type-check the package with `mcs` against the real API's
// shapes (tests/tests/unity_package.rs); nothing here runs. In 5.1 the
// file-path methods (SetMp4DatasetFilePath, StartPlayback) are current; 6.1
// deprecates them for the *Uri variants.
using System;
using UnityEngine.XR.ARSubsystems;

namespace UnityEngine.XR.ARCore
{
    public enum ArStatus
    {
        Success = 0,
        ErrorInvalidArgument = -1,
        ErrorFatal = -2,
        ErrorSessionPaused = -3,
        ErrorSessionNotPaused = -4,
        ErrorIllegalState = -20,
        ErrorRecordingFailed = -23,
        ErrorPlaybackFailed = -24,
        ErrorSessionUnsupported = -25,
    }

    public enum ArPlaybackStatus
    {
        None = 0,
        Ok = 1,
        IOError = 2,
        Finished = 3,
    }

    public static class ArPlaybackStatusExtensions
    {
        public static bool Playing(this ArPlaybackStatus status) { throw null; }
    }

    public struct ArSession : IEquatable<ArSession>
    {
        public bool Equals(ArSession other) { throw null; }
    }

    public struct ArRecordingConfig : IEquatable<ArRecordingConfig>, IDisposable
    {
        public ArRecordingConfig(ArSession session) { throw null; }
        public void SetMp4DatasetFilePath(ArSession session, string path) { throw null; }
        public void Dispose() { throw null; }
        public bool Equals(ArRecordingConfig other) { throw null; }
    }

    public sealed class ARCoreSessionSubsystem : XRSessionSubsystem
    {
        public ArSession session { get { throw null; } }
        public ArStatus StartRecording(ArRecordingConfig recordingConfig) { throw null; }
        public ArStatus StopRecording() { throw null; }
        public ArStatus StartPlayback(string playbackDataset) { throw null; }
        public ArPlaybackStatus playbackStatus { get { throw null; } }
    }
}
