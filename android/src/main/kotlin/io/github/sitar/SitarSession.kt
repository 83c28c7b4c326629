package io.github.sitar

import java.nio.ByteBuffer

/**
 * One recording session on the user's AR device: record (start, frame,
 * depth, stop), upload, then visualise results (error at a time, markers,
 * render plan). Every method throws [SitarException] on error; after
 * [close] every call throws one with status [SitarStatus.INVALID_HANDLE].
 * Safe to use from several threads.
 */
class SitarSession private constructor(handle: Long) : AutoCloseable {
    @Volatile private var handle: Long = handle

    /** A new session from its JSON config (every key optional; "{}" = defaults; keys in `rust/core/README.md`). */
    constructor(configJson: String = "{}") : this(Native.sessionNew(configJson))

    /** Starts recording (frame 0). */
    fun start(tNs: Long, pose: Pose) = Native.sessionStart(handle, tNs, pose.px, pose.py, pose.pz, pose.qx, pose.qy, pose.qz, pose.qw)

    /** One camera frame; returns flags ([MIDPOINT]: give depth now, [ENDPOINT]). */
    fun frame(tNs: Long, pose: Pose): Int = frame(tNs, pose.px, pose.py, pose.pz, pose.qx, pose.qy, pose.qz, pose.qw)

    /** Allocation-free variant of [frame] for the per-frame path. */
    fun frame(tNs: Long, px: Double, py: Double, pz: Double, qx: Double, qy: Double, qz: Double, qw: Double): Int =
        Native.sessionFrame(handle, tNs, px, py, pz, qx, qy, qz, qw)

    /**
     * The depth image (16-bit millimetres, sensor orientation) for the last
     * midpoint, from a *direct* buffer such as ARCore's `Image.planes[0].buffer`.
     * [displayRotation] is 0, 90, 180 or 270 (clockwise, sensor to display).
     */
    fun depth(buffer: ByteBuffer, width: Int, height: Int, rowStrideBytes: Int, k: Intrinsics, displayRotation: Int) =
        Native.sessionDepthBuffer(handle, buffer, width, height, rowStrideBytes, k.fx, k.fy, k.cx, k.cy, displayRotation)

    /** As [depth] with the samples in a `ShortArray` (row stride in bytes). */
    fun depth(data: ShortArray, width: Int, height: Int, rowStrideBytes: Int, k: Intrinsics, displayRotation: Int) =
        Native.sessionDepthArray(handle, data, width, height, rowStrideBytes, k.fx, k.fy, k.cx, k.cy, displayRotation)

    /**
     * The camera's luminance plane (ARCore `Image.planes[0].buffer`, sensor orientation) for
     * the latest midpoint: give it when [frame] returns the midpoint bit (1), with that frame's
     * image. Keeps a display-oriented JPEG thumbnail and the image properties; a no-op with
     * `"images": false` in the config.
     */
    fun image(buffer: ByteBuffer, width: Int, height: Int, rowStrideBytes: Int, displayRotation: Int) =
        Native.sessionImageBuffer(handle, buffer, width, height, rowStrideBytes, displayRotation)

    /** As [image] with the plane in a `ByteArray` (row stride in bytes). */
    fun image(data: ByteArray, width: Int, height: Int, rowStrideBytes: Int, displayRotation: Int) =
        Native.sessionImageArray(handle, data, width, height, rowStrideBytes, displayRotation)

    /** What the camera saw at sub-trajectory [k], how it moved, its depth and likely causes. */
    fun evidence(k: Int): Evidence = Evidence.of(Native.sessionSubtrajectoryEvidence(handle, k))

    /** The greyscale JPEG thumbnail of sub-trajectory [k] (empty without an image), e.g. for
     * `BitmapFactory.decodeByteArray`. */
    fun thumbnail(k: Int): ByteArray = Native.sessionThumbnail(handle, k)

    /** Stops recording. */
    fun stop(tNs: Long, pose: Pose): Summary =
        Summary.of(Native.sessionStop(handle, tNs, pose.px, pose.py, pose.pz, pose.qx, pose.qy, pose.qz, pose.qw))

    /** The summary of a stopped recording. */
    fun summary(): Summary = Summary.of(Native.sessionSummary(handle))

    /**
     * Loads results: legacy CSV (`start,error`) or JSON. Results for another window length
     * than the config's `subtrajectory_frames`, or another `pose_relation`, are refused
     * ([SitarStatus.INVALID_ARGUMENT]).
     */
    fun loadResults(csvOrJson: String) = Native.sessionLoadResults(handle, csvOrJson)

    /**
     * Class and error at a timestamp (nearest result window within tolerance). The class is
     * that of the value the config's `classify_by` picks: the error (`"estimate"`, default)
     * or, with `"upper"`, the window's upper bound where the results give one.
     */
    fun errorAt(tNs: Long): ErrorAt = ErrorAt.of(Native.sessionErrorAt(handle, tNs))

    /**
     * The interval of the result window [errorAt] finds at [tNs], when the loaded results
     * are calibrated; null when no window is near, no results are loaded, or they are not
     * calibrated.
     */
    fun boundsAt(tNs: Long): ErrorBounds? = ErrorBounds.of(Native.sessionBoundsAt(handle, tNs))

    /** The name of the calibration of the loaded results; null when they are not calibrated. */
    fun resultsCalibration(): String? = Native.sessionResultsCalibration(handle).ifEmpty { null }

    /**
     * Takes a calibration (the JSON file `sitar calibrate` writes, e.g. bundled in the app's
     * assets) so the walk is coloured the moment it [stop]s, offline: every sub-trajectory gets
     * the calibrated error and interval of the walk alone, the markers their places. Given
     * after [stop] it colours at once, unless the backend's results are loaded; the backend's
     * results replace the walk's when they arrive ([resultsProvenance] says which). Malformed
     * JSON is [SitarStatus.PARSE]; a calibration for another window (`subtrajectory_frames`) or
     * `pose_relation`, or without a model for one run, [SitarStatus.INVALID_ARGUMENT], naming
     * what differs. A refused calibration changes nothing.
     */
    fun setCalibration(json: String) = Native.sessionSetCalibration(handle, json)

    /**
     * Where the loaded results come from: the walk itself or replays, how many runs, and
     * whether the colours are a guess ([Provenance.isGuess]).
     */
    fun resultsProvenance(): Provenance = Provenance.of(Native.sessionResultsProvenance(handle))

    /** The class of sub-trajectory [k]. */
    fun subtrajectoryClass(k: Int): ErrorClass = ErrorClass.of(Native.sessionSubtrajectoryClass(handle, k))

    /** The markers (needs results). */
    fun markers(): List<Marker> = Marker.list(Native.sessionMarkers(handle))

    /** Every sub-trajectory's error and class, in order (all unknown before results arrive). */
    fun results(): List<SubtrajectoryResult> = SubtrajectoryResult.list(Native.sessionSubtrajectoryResults(handle))

    /** Whether the loaded results are too noisy to trust (show a warning). */
    fun resultsUnreliable(): Boolean = Native.sessionResultsUnreliable(handle)

    /** What to draw: segments, joints, frustums, start and stop, each with its class. */
    fun renderPlan(): RenderPlan = RenderPlan.of(Native.sessionRenderPlan(handle))

    /**
     * An observation of the venue's anchor image: the pose ARCore reports for the
     * `AugmentedImage` (`centerPose`, world-from-image; image +X to its right) and its
     * tracking state. An empty or over-long id (> 64 bytes), a non-finite pose or an unknown
     * tracking value is [SitarStatus.INVALID_ARGUMENT]; before start or after stop
     * [SitarStatus.INVALID_STATE].
     */
    fun anchor(tNs: Long, anchorId: String, imagePose: Pose, tracking: Tracking) =
        Native.sessionAnchor(handle, tNs, anchorId, imagePose.px, imagePose.py, imagePose.pz,
            imagePose.qx, imagePose.qy, imagePose.qz, imagePose.qw, tracking.code)

    /** Loads the venue's `map.json`; the session is aligned once its anchor is fully tracked. */
    fun loadVenue(mapJson: String) = Native.sessionLoadVenue(handle, mapJson)

    /** The venue's cells in this session's world frame ([SitarStatus.INVALID_STATE] before the anchor is fully tracked). */
    fun venueCells(): List<VenueCell> = VenueCell.list(Native.sessionVenueCells(handle))

    /**
     * Where each marker ([markers] order), then each high venue surface cell, is shown on a
     * [widthPx] × [heightPx] screen seen by [camera] (the display-oriented camera pose) with
     * vertical field of view [vfovDeg]; off-screen targets are pinned to the ellipse
     * [marginPx] inside the edges, keeping their side when behind the camera.
     */
    fun guide(camera: Pose, vfovDeg: Double, widthPx: Int, heightPx: Int, marginPx: Double): List<Guide> =
        Guide.list(Native.sessionGuide(handle, camera.px, camera.py, camera.pz, camera.qx, camera.qy,
            camera.qz, camera.qw, vfovDeg, widthPx, heightPx, marginPx))

    /** The logged poses as TUM text (integer nanoseconds). */
    fun trajectoryTum(): String = Native.sessionTrajectoryTum(handle)

    /** Saves the session folder [dir]. */
    fun save(dir: String) = Native.sessionSave(handle, dir)

    /** Writes the scene as a glTF 2.0 binary file (.glb) at [path]: trajectory by class, frustums, markers, surface points. */
    fun exportGltf(path: String) = Native.sessionExportGltf(handle, path)

    /**
     * Uploads the recording in the background; when the server is done the
     * results are loaded into this session ([UploadJob.progress] tells).
     * [optionsJson]: `server_url` (else the config's), `server_token` (the backend's access
     * token), `server_cert_sha256` (pins the backend's TLS certificate by its SHA-256
     * fingerprint; a different one fails the job with `SITAR_ERR_NETWORK`), `trials`, `setting`,
     * `playback`, `poll_interval_ms`, `session_id` (continue that server session, e.g. a
     * failed job's [UploadJob.serverId]: the upload resumes where the server's copy ends),
     * `window_frames` and `pose_relation` (default: the config's `subtrajectory_frames` and
     * `pose_relation`; other values are refused).
     */
    fun upload(recordingPath: String, optionsJson: String = ""): UploadJob {
        val job = UploadJob(Native.uploadStart(handle, recordingPath, optionsJson))
        lastUpload = job
        return job
    }

    @Volatile private var lastUpload: UploadJob? = null

    /** Progress of the latest [upload] (null if none was started). */
    fun progress(): UploadProgress? = lastUpload?.progress()

    /** Frees the native session exactly once; later calls are harmless. */
    @Synchronized
    override fun close() {
        val h = handle
        if (h != 0L) {
            handle = 0L
            Native.sessionFree(h)
        }
    }

    companion object {
        /** Frame flag: a midpoint, give the depth image now. */
        const val MIDPOINT = 1
        /** Frame flag: a sub-trajectory is complete. */
        const val ENDPOINT = 2

        /** The native library version. */
        @JvmStatic fun version(): String = Native.version()

        /** Loads a saved session folder. */
        @JvmStatic fun load(dir: String): SitarSession = SitarSession(Native.sessionLoad(dir))
    }
}

/** A background upload; [close] frees the handle and cancels a running job. */
class UploadJob internal constructor(handle: Long) : AutoCloseable {
    @Volatile private var handle: Long = handle

    /** A snapshot (never blocks on the network). */
    fun progress(): UploadProgress = UploadProgress.of(Native.uploadProgress(handle))

    /** Why the job failed ("" otherwise). */
    fun message(): String = Native.uploadMessage(handle)

    /** The server's session id ("" until created). */
    fun serverId(): String = Native.uploadServerId(handle)

    /** Cancels: the state is [UploadState.CANCELLED] at once. */
    fun cancel() = Native.uploadCancel(handle)

    @Synchronized
    override fun close() {
        val h = handle
        if (h != 0L) {
            handle = 0L
            Native.uploadFree(h)
        }
    }
}

/** The playback-device logger: logs every frame, writes `trajectory_N.txt`. */
class PlaybackLogger(configJson: String = "{}") : AutoCloseable {
    @Volatile private var handle: Long = Native.playbackNew(configJson)

    /** Logs one frame's pose. */
    fun log(tNs: Long, pose: Pose) = Native.playbackLog(handle, tNs, pose.px, pose.py, pose.pz, pose.qx, pose.qy, pose.qz, pose.qw)

    /** Number of poses logged. */
    val size: Long get() = Native.playbackLen(handle)

    /** The poses as TUM text. */
    fun tum(): String = Native.playbackTum(handle)

    /** Writes `<dir>/trajectory_<index>.txt` and returns its path. */
    fun write(dir: String, index: Int): String = Native.playbackWrite(handle, dir, index)

    @Synchronized
    override fun close() {
        val h = handle
        if (h != 0L) {
            handle = 0L
            Native.playbackFree(h)
        }
    }
}
