package com.google.ar.core.exceptions;
public class UnavailableArcoreNotInstalledException extends UnavailableException {
    public UnavailableArcoreNotInstalledException() { throw new RuntimeException("Stub!"); }
    public UnavailableArcoreNotInstalledException(String message) { throw new RuntimeException("Stub!"); }
}
