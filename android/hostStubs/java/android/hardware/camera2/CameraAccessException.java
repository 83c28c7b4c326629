package android.hardware.camera2;
public class CameraAccessException extends android.util.AndroidException {
    public CameraAccessException(int problem) { super(); throw new RuntimeException("Stub!"); }
}
