package com.google.ar.core.exceptions;
public class UnavailableDeviceNotCompatibleException extends UnavailableException {
    public UnavailableDeviceNotCompatibleException() { throw new RuntimeException("Stub!"); }
    public UnavailableDeviceNotCompatibleException(String message) { throw new RuntimeException("Stub!"); }
}
