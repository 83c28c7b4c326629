package com.google.ar.core;
import com.google.ar.core.exceptions.*;
public class Session {
    public Session(android.content.Context context) throws UnavailableArcoreNotInstalledException, UnavailableApkTooOldException, UnavailableSdkTooOldException, UnavailableDeviceNotCompatibleException { throw new RuntimeException("Stub!"); }
    public void configure(Config config) { throw new RuntimeException("Stub!"); }
    public Config getConfig() { throw new RuntimeException("Stub!"); }
    public boolean isDepthModeSupported(Config.DepthMode mode) { throw new RuntimeException("Stub!"); }
    public CameraConfig getCameraConfig() { throw new RuntimeException("Stub!"); }
    public void resume() throws CameraNotAvailableException { throw new RuntimeException("Stub!"); }
    public void pause() { throw new RuntimeException("Stub!"); }
    public void close() { throw new RuntimeException("Stub!"); }
    public Frame update() throws CameraNotAvailableException { throw new RuntimeException("Stub!"); }
    public void setCameraTextureName(int textureId) { throw new RuntimeException("Stub!"); }
    public void setDisplayGeometry(int displayRotation, int widthPx, int heightPx) { throw new RuntimeException("Stub!"); }
    public void setPlaybackDatasetUri(android.net.Uri mp4DatasetUri) throws PlaybackFailedException { throw new RuntimeException("Stub!"); }
    public PlaybackStatus getPlaybackStatus() { throw new RuntimeException("Stub!"); }
    public void startRecording(RecordingConfig recordingConfig) throws RecordingFailedException { throw new RuntimeException("Stub!"); }
    public void stopRecording() throws RecordingFailedException { throw new RuntimeException("Stub!"); }
    public RecordingStatus getRecordingStatus() { throw new RuntimeException("Stub!"); }
}
