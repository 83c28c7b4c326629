package com.google.ar.core;

public class AugmentedImage implements Trackable {
    @Override public TrackingState getTrackingState() { throw new RuntimeException("Stub!"); }
    public String getName() { throw new RuntimeException("Stub!"); }
    public int getIndex() { throw new RuntimeException("Stub!"); }
    public Pose getCenterPose() { throw new RuntimeException("Stub!"); }
    public float getExtentX() { throw new RuntimeException("Stub!"); }
    public TrackingMethod getTrackingMethod() { throw new RuntimeException("Stub!"); }
    public enum TrackingMethod { NOT_TRACKING, FULL_TRACKING, LAST_KNOWN_POSE }
}
