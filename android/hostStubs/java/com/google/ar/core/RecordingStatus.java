package com.google.ar.core;
public enum RecordingStatus { NONE, OK, IO_ERROR }
