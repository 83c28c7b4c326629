package com.google.ar.core;
public class Camera {
    public Pose getDisplayOrientedPose() { throw new RuntimeException("Stub!"); }
    public TrackingState getTrackingState() { throw new RuntimeException("Stub!"); }
    public CameraIntrinsics getImageIntrinsics() { throw new RuntimeException("Stub!"); }
    public void getViewMatrix(float[] viewMatrix, int offset) { throw new RuntimeException("Stub!"); }
    public void getProjectionMatrix(float[] dest, int offset, float near, float far) { throw new RuntimeException("Stub!"); }
}
