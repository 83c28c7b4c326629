package com.google.ar.core;
public class CameraConfig {
    public String getCameraId() { throw new RuntimeException("Stub!"); }
}
