package com.google.ar.core.exceptions;
public class UnavailableSdkTooOldException extends UnavailableException {
    public UnavailableSdkTooOldException() { throw new RuntimeException("Stub!"); }
    public UnavailableSdkTooOldException(String message) { throw new RuntimeException("Stub!"); }
}
