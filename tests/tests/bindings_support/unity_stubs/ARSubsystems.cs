// Stubs of the AR Subsystems API (com.unity.xr.arfoundation 5.1, assembly
// Unity.XR.ARSubsystems) used by unity-plugin/Runtime. They exist only to
// type-check the package with `mcs` against the real API's shapes
// (tests/tests/unity_package.rs); nothing here runs. The real
// XRSessionSubsystem derives from SubsystemWithProvider<…>; that chain is
// left out (the package only type-tests the subsystem).
using System;
using Unity.Collections;

namespace UnityEngine.XR.ARSubsystems
{
    public struct XRCpuImage : IDisposable, IEquatable<XRCpuImage>
    {
        public struct Plane : IEquatable<Plane>
        {
            public int rowStride { get { throw null; } }
            public int pixelStride { get { throw null; } }
            public NativeArray<byte> data { get { throw null; } }
            public bool Equals(Plane other) { throw null; }
        }

        public int width { get { throw null; } }
        public int height { get { throw null; } }
        public Plane GetPlane(int planeIndex) { throw null; }
        public void Dispose() { throw null; }
        public bool Equals(XRCpuImage other) { throw null; }
    }

    public struct XRCameraIntrinsics : IEquatable<XRCameraIntrinsics>
    {
        public Vector2 focalLength { get { throw null; } }
        public Vector2 principalPoint { get { throw null; } }
        public Vector2Int resolution { get { throw null; } }
        public bool Equals(XRCameraIntrinsics other) { throw null; }
    }

    public class XRSessionSubsystem
    {
        public abstract class Provider { }
    }

    public class XRSessionSubsystemDescriptor { }

    public enum TrackingState
    {
        None = 0,
        Limited = 1,
        Tracking = 2,
    }

    public struct XRReferenceImage : IEquatable<XRReferenceImage>
    {
        public string name { get { throw null; } }
        public bool Equals(XRReferenceImage other) { throw null; }
    }
}
