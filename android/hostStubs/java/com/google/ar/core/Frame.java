package com.google.ar.core;
public class Frame {
    public long getTimestamp() { throw new RuntimeException("Stub!"); }
    public <T extends Trackable> java.util.Collection<T> getUpdatedTrackables(Class<T> filterType) { throw new RuntimeException("Stub!"); }
    public Camera getCamera() { throw new RuntimeException("Stub!"); }
    public boolean hasDisplayGeometryChanged() { throw new RuntimeException("Stub!"); }
    public void transformCoordinates2d(Coordinates2d inputCoordinates, java.nio.FloatBuffer inputVertices2d, Coordinates2d outputCoordinates, java.nio.FloatBuffer outputVertices2d) { throw new RuntimeException("Stub!"); }
    public android.media.Image acquireCameraImage() throws com.google.ar.core.exceptions.NotYetAvailableException { throw new RuntimeException("Stub!"); }
    public android.media.Image acquireDepthImage16Bits() throws com.google.ar.core.exceptions.NotYetAvailableException { throw new RuntimeException("Stub!"); }
}
