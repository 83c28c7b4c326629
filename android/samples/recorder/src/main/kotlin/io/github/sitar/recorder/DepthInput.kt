package io.github.sitar.recorder

import io.github.sitar.Intrinsics

/**
 * The clockwise rotation (0, 90, 180, 270) from the camera sensor image to the
 * display, which `SitarSession.depth` takes: the back camera's
 * [sensorOrientationDeg] (`CameraCharacteristics.SENSOR_ORIENTATION`, 90 on most
 * phones) minus the display's rotation ([surfaceRotation] is `Surface.ROTATION_*`:
 * 0, 1, 2, 3 for 0°, 90°, 180°, 270°).
 */
fun displayRotationDeg(sensorOrientationDeg: Int, surfaceRotation: Int): Int {
    require(surfaceRotation in 0..3) { "surface rotation $surfaceRotation: expected Surface.ROTATION_0 … ROTATION_270" }
    return ((sensorOrientationDeg - 90 * surfaceRotation) % 360 + 360) % 360
}

/**
 * ARCore's camera intrinsics are for the CPU camera image ([imageWidth] ×
 * [imageHeight]); the depth image is smaller: scale them to its [depthWidth] ×
 * [depthHeight] pixels.
 */
fun depthIntrinsics(
    focalLength: FloatArray, principalPoint: FloatArray, imageWidth: Int, imageHeight: Int,
    depthWidth: Int, depthHeight: Int
): Intrinsics {
    require(imageWidth > 0 && imageHeight > 0) { "camera image ${imageWidth}x$imageHeight" }
    val sx = depthWidth.toDouble() / imageWidth
    val sy = depthHeight.toDouble() / imageHeight
    return Intrinsics(focalLength[0] * sx, focalLength[1] * sy, principalPoint[0] * sx, principalPoint[1] * sy)
}
