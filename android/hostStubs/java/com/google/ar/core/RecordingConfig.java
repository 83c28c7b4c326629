package com.google.ar.core;
public class RecordingConfig {
    public RecordingConfig(Session session) { throw new RuntimeException("Stub!"); }
    public RecordingConfig setMp4DatasetUri(android.net.Uri mp4DatasetUri) { throw new RuntimeException("Stub!"); }
    public RecordingConfig setAutoStopOnPause(boolean autoStopOnPause) { throw new RuntimeException("Stub!"); }
}
