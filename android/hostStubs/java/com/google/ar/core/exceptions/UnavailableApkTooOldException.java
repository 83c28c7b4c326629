package com.google.ar.core.exceptions;
public class UnavailableApkTooOldException extends UnavailableException {
    public UnavailableApkTooOldException() { throw new RuntimeException("Stub!"); }
    public UnavailableApkTooOldException(String message) { throw new RuntimeException("Stub!"); }
}
