package com.google.ar.core;
public class CameraIntrinsics {
    public float[] getFocalLength() { throw new RuntimeException("Stub!"); }
    public float[] getPrincipalPoint() { throw new RuntimeException("Stub!"); }
    public int[] getImageDimensions() { throw new RuntimeException("Stub!"); }
}
