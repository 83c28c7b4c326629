package com.google.ar.core.exceptions;
public class CameraNotAvailableException extends Exception {
    public CameraNotAvailableException() { throw new RuntimeException("Stub!"); }
    public CameraNotAvailableException(String message) { throw new RuntimeException("Stub!"); }
}
