package com.google.ar.core;

public class AugmentedImageDatabase {
    public AugmentedImageDatabase(Session session) { throw new RuntimeException("Stub!"); }
    public int addImage(String name, android.graphics.Bitmap bitmap, float widthInMeters) { throw new RuntimeException("Stub!"); }
    public int getNumImages() { throw new RuntimeException("Stub!"); }
}
