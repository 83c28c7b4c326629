// Generated from rust/ffi/src/exports.rs by rust/ffi/tests/generated_bindings.rs; do not edit.
// Regenerate: SITAR_REGENERATE=1 cargo test -p sitar-ffi --test generated_bindings
package io.github.sitar

import java.nio.ByteBuffer

/**
 * The JNI entry points of `libsitar.so` (`Java_io_github_sitar_Native_*`, declared
 * once in `rust/ffi/src/exports.rs`). Errors arrive as [SitarException]. Structs come
 * back as flat `DoubleArray`s whose offsets are in `Layouts.kt`. Use [SitarSession].
 */
internal object Native {
    init {
        System.loadLibrary("sitar")
    }

    @JvmStatic external fun version(): String

    @JvmStatic external fun sessionNew(configJson: String): Long
    @JvmStatic external fun sessionFree(h: Long)
    @JvmStatic external fun sessionStart(h: Long, tNs: Long, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double)
    @JvmStatic external fun sessionFrame(h: Long, tNs: Long, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double): Int
    @JvmStatic external fun sessionDepthBuffer(h: Long, buffer: ByteBuffer, width: Int, height: Int, rowStrideBytes: Int, fx: Double, fy: Double, cx: Double, cy: Double, displayRotation: Int)
    @JvmStatic external fun sessionDepthArray(h: Long, data: ShortArray, width: Int, height: Int, rowStrideBytes: Int, fx: Double, fy: Double, cx: Double, cy: Double, displayRotation: Int)
    @JvmStatic external fun sessionImageBuffer(h: Long, luma: ByteBuffer, width: Int, height: Int, rowStrideBytes: Int, displayRotation: Int)
    @JvmStatic external fun sessionImageArray(h: Long, luma: ByteArray, width: Int, height: Int, rowStrideBytes: Int, displayRotation: Int)
    @JvmStatic external fun sessionSubtrajectoryEvidence(h: Long, k: Int): DoubleArray
    @JvmStatic external fun sessionThumbnail(h: Long, k: Int): ByteArray
    @JvmStatic external fun sessionStop(h: Long, tNs: Long, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double): DoubleArray
    @JvmStatic external fun sessionSummary(h: Long): DoubleArray
    @JvmStatic external fun sessionLoadResults(h: Long, csvOrJson: String)
    @JvmStatic external fun sessionErrorAt(h: Long, tNs: Long): DoubleArray
    @JvmStatic external fun sessionBoundsAt(h: Long, tNs: Long): DoubleArray
    @JvmStatic external fun sessionResultsCalibration(h: Long): String
    @JvmStatic external fun sessionSetCalibration(h: Long, json: String)
    @JvmStatic external fun sessionResultsProvenance(h: Long): DoubleArray
    @JvmStatic external fun sessionMarkers(h: Long): DoubleArray
    @JvmStatic external fun sessionResultsUnreliable(h: Long): Boolean
    @JvmStatic external fun sessionSubtrajectoryClass(h: Long, k: Int): Int
    @JvmStatic external fun sessionSubtrajectoryResults(h: Long): DoubleArray
    @JvmStatic external fun sessionRenderPlan(h: Long): DoubleArray
    @JvmStatic external fun sessionTrajectoryTum(h: Long): String
    @JvmStatic external fun sessionSave(h: Long, dir: String)
    @JvmStatic external fun sessionExportGltf(h: Long, path: String)
    @JvmStatic external fun sessionAnchor(h: Long, tNs: Long, anchorId: String, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double, tracking: Int)
    @JvmStatic external fun sessionLoadVenue(h: Long, mapJson: String)
    @JvmStatic external fun sessionVenueCells(h: Long): DoubleArray
    @JvmStatic external fun sessionGuide(h: Long, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double, vfovDeg: Double, widthPx: Int, heightPx: Int, marginPx: Double): DoubleArray
    @JvmStatic external fun sessionLoad(dir: String): Long

    @JvmStatic external fun playbackNew(configJson: String): Long
    @JvmStatic external fun playbackLog(h: Long, tNs: Long, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double)
    @JvmStatic external fun playbackLen(h: Long): Long
    @JvmStatic external fun playbackTum(h: Long): String
    @JvmStatic external fun playbackWrite(h: Long, dir: String, index: Int): String
    @JvmStatic external fun playbackFree(h: Long)

    @JvmStatic external fun uploadStart(h: Long, recordingPath: String, optionsJson: String?): Long
    @JvmStatic external fun uploadProgress(job: Long): DoubleArray
    @JvmStatic external fun uploadMessage(job: Long): String
    @JvmStatic external fun uploadServerId(job: Long): String
    @JvmStatic external fun uploadCancel(job: Long)
    @JvmStatic external fun uploadFree(job: Long)

    @JvmStatic external fun platformTlsInit(context: Any): Boolean

    /** Only in builds with the `testing` feature. */
    @JvmStatic external fun testingPanic()
}
