package com.google.ar.core.exceptions;
public class NotYetAvailableException extends Exception {
    public NotYetAvailableException() { throw new RuntimeException("Stub!"); }
    public NotYetAvailableException(String message) { throw new RuntimeException("Stub!"); }
}
