// Stubs of the AR Foundation API (com.unity.xr.arfoundation 5.1, assembly
// Unity.XR.ARFoundation) used by unity-plugin/Runtime. They exist only to
// type-check the package with `mcs` against the real API's shapes
// (tests/tests/unity_package.rs); nothing here runs. The real
// SubsystemLifecycleManager constrains its type parameters to the subsystem
// types (left out here); ARCameraManager and AROcclusionManager derive from it
// too, but the package uses none of its members on them.
using System;
using System.Collections.Generic;
using UnityEngine.XR.ARSubsystems;

namespace UnityEngine.XR.ARFoundation
{
    public class SubsystemLifecycleManager<TSubsystem, TSubsystemDescriptor, TProvider> : MonoBehaviour
    {
        public TSubsystem subsystem { get { throw null; } private set { throw null; } }
    }

    public sealed class ARSession
        : SubsystemLifecycleManager<XRSessionSubsystem, XRSessionSubsystemDescriptor, XRSessionSubsystem.Provider>
    {
    }

    public struct ARCameraFrameEventArgs : IEquatable<ARCameraFrameEventArgs>
    {
        public long? timestampNs { get { throw null; } set { throw null; } }
        public bool Equals(ARCameraFrameEventArgs other) { throw null; }
    }

    public sealed class ARCameraManager : MonoBehaviour
    {
        public event Action<ARCameraFrameEventArgs> frameReceived { add { throw null; } remove { throw null; } }
        public bool TryGetIntrinsics(out XRCameraIntrinsics cameraIntrinsics) { throw null; }
        public bool TryAcquireLatestCpuImage(out XRCpuImage cpuImage) { throw null; }
    }

    public sealed class AROcclusionManager : MonoBehaviour
    {
        public bool TryAcquireEnvironmentDepthCpuImage(out XRCpuImage cpuImage) { throw null; }
    }

    /// <summary>The real one derives from ARTrackable&lt;XRTrackedImage, ARTrackedImage&gt;.</summary>
    public sealed class ARTrackedImage : MonoBehaviour
    {
        public XRReferenceImage referenceImage { get { throw null; } }
        public TrackingState trackingState { get { throw null; } }
        public Vector2 size { get { throw null; } }
    }

    public struct ARTrackedImagesChangedEventArgs : IEquatable<ARTrackedImagesChangedEventArgs>
    {
        public List<ARTrackedImage> added { get { throw null; } }
        public List<ARTrackedImage> updated { get { throw null; } }
        public List<ARTrackedImage> removed { get { throw null; } }
        public bool Equals(ARTrackedImagesChangedEventArgs other) { throw null; }
    }

    /// <summary>The real one derives from ARTrackableManager&lt;…&gt;.</summary>
    public sealed class ARTrackedImageManager : MonoBehaviour
    {
        public event Action<ARTrackedImagesChangedEventArgs> trackedImagesChanged { add { throw null; } remove { throw null; } }
    }
}
