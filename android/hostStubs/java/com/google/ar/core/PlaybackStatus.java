package com.google.ar.core;
public enum PlaybackStatus { NONE, OK, IO_ERROR, FINISHED }
