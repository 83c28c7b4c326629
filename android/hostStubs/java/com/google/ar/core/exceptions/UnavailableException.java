package com.google.ar.core.exceptions;
public class UnavailableException extends Exception {
    public UnavailableException() { throw new RuntimeException("Stub!"); }
    public UnavailableException(String message) { throw new RuntimeException("Stub!"); }
}
