package com.google.ar.core.exceptions;
public class PlaybackFailedException extends Exception {
    public PlaybackFailedException() { throw new RuntimeException("Stub!"); }
    public PlaybackFailedException(String message) { throw new RuntimeException("Stub!"); }
}
