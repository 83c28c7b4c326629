package com.google.ar.core;
public class Pose {
    public float tx() { throw new RuntimeException("Stub!"); }
    public float ty() { throw new RuntimeException("Stub!"); }
    public float tz() { throw new RuntimeException("Stub!"); }
    public float qx() { throw new RuntimeException("Stub!"); }
    public float qy() { throw new RuntimeException("Stub!"); }
    public float qz() { throw new RuntimeException("Stub!"); }
    public float qw() { throw new RuntimeException("Stub!"); }
}
