package com.google.ar.core.exceptions;
public class RecordingFailedException extends Exception {
    public RecordingFailedException() { throw new RuntimeException("Stub!"); }
    public RecordingFailedException(String message) { throw new RuntimeException("Stub!"); }
}
