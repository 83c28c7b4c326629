package android.hardware.camera2;
public final class CameraManager {
    public CameraCharacteristics getCameraCharacteristics(String cameraId) throws CameraAccessException { throw new RuntimeException("Stub!"); }
}
