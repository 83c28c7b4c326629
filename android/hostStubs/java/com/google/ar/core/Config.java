package com.google.ar.core;
public class Config {
    public Config(Session session) { throw new RuntimeException("Stub!"); }
    public Config setDepthMode(DepthMode mode) { throw new RuntimeException("Stub!"); }
    public Config setAugmentedImageDatabase(AugmentedImageDatabase augmentedImageDatabase) { throw new RuntimeException("Stub!"); }
    public DepthMode getDepthMode() { throw new RuntimeException("Stub!"); }
    public enum DepthMode { DISABLED, AUTOMATIC, RAW_DEPTH_ONLY }
}
