package android.hardware.camera2;
public final class CameraCharacteristics {
    public static final Key<Integer> SENSOR_ORIENTATION = null;
    public <T> T get(Key<T> key) { throw new RuntimeException("Stub!"); }
    public static final class Key<T> {
        private Key() { throw new RuntimeException("Stub!"); }
    }
}
