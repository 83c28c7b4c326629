package android.graphics;
public final class Bitmap {
    public final int getWidth() { throw new RuntimeException("Stub!"); }
}
