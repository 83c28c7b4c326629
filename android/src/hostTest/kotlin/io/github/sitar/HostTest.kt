package io.github.sitar

import java.io.File
import java.net.ServerSocket
import java.nio.ByteBuffer
import java.nio.ByteOrder

// Host test of the Kotlin wrapper against the host-built libsitar.so (run by
// tests/tests/bindings_kotlin.rs): a whole session and every error path.
// Args: <expected version> <temp dir>. Prints "PASSED n checks" on success.

private var checks = 0

private fun check(condition: Boolean, what: String) {
    checks++
    if (!condition) throw AssertionError("check failed: $what")
}

private fun near(a: Double, b: Double, what: String, eps: Double = 1e-9) = check(Math.abs(a - b) <= eps, "$what: $a vs $b")

private fun expectSitar(status: SitarStatus, needle: String, block: () -> Unit) {
    try {
        block()
    } catch (e: SitarException) {
        check(e.status == status && e.code == status.code, "expected $status, got ${e.code}: ${e.message}")
        check((e.message ?: "").contains(needle), "message '${e.message}' should mention '$needle'")
        return
    }
    throw AssertionError("expected SitarException($status) mentioning '$needle'")
}

private const val FRAME_NS = 33_333_333L
private const val STEP_M = 0.1
private val ERRORS = doubleArrayOf(0.01, 0.12, 0.06, 0.01, 0.2, 0.03)
private const val W = 160
private const val H = 120
private val K = Intrinsics(150.0, 150.0, 80.0, 60.0)

private fun poseAt(frame: Long) = Pose(frame * STEP_M, 1.5, 0.0, 0.0, 0.0, 0.0, 1.0)

private fun classOf(e: Double) = if (e >= 0.10) ErrorClass.HIGH else if (e >= 0.05) ErrorClass.MEDIUM else ErrorClass.LOW

private fun resultsCsv(): String {
    val sb = StringBuilder("start,error\n")
    for (k in ERRORS.indices) sb.append(10L * k * FRAME_NS).append(',').append(ERRORS[k]).append('\n')
    return sb.toString()
}

/** Results JSON as the backend writes it, one window per 10-frame sub-trajectory. */
private fun resultsJson(windowFrames: Int, relation: String, unit: String, errors: DoubleArray): String {
    val key = if (unit == "deg") "error_deg" else "error_m"
    val windows = errors.indices.joinToString(",") { k -> """{"start":${10L * k * FRAME_NS},"$key":${errors[k]},"pairs":3}""" }
    return """{"version":1,"setting":"trim_mean_30","trials":3,"window_frames":$windowFrames,"pose_relation":"$relation","unit":"$unit","windows":[$windows]}"""
}

private fun record(s: SitarSession): Summary {
    val array = ShortArray(W * H) { 2000 }
    val buffer = ByteBuffer.allocateDirect(W * H * 2).order(ByteOrder.nativeOrder())
    for (i in 0 until W * H) buffer.putShort(2000)
    buffer.rewind()
    s.start(0, poseAt(0))
    var midpoints = 0
    for (i in 1L..60L) {
        val flags = s.frame(i * FRAME_NS, poseAt(i))
        val expected = when (i % 10) { 5L -> SitarSession.MIDPOINT; 0L -> SitarSession.ENDPOINT; else -> 0 }
        check(flags == expected, "flags of frame $i: $flags")
        if (flags == SitarSession.MIDPOINT) {
            // Alternate the two depth paths: direct ByteBuffer and ShortArray.
            if (midpoints % 2 == 0) s.depth(buffer, W, H, W * 2, K, 0) else s.depth(array, W, H, W * 2, K, 0)
            midpoints++
        }
    }
    return s.stop(61 * FRAME_NS, poseAt(61))
}

private fun wholeSession(tmp: File) {
    val s = SitarSession("""{"convention":"unity"}""")
    val summary = record(s)
    check(summary.frames == 60 && summary.midpoints == 6 && summary.subtrajectories == 6 && summary.depthSamples == 6, "$summary")
    near(summary.durationS, 61.0 * FRAME_NS / 1e9, "duration")
    near(summary.lengthM, 6.1, "length", 1e-12)
    near(summary.meanDepthM, 2.0, "mean depth")
    check(s.summary() == summary, "summary again")

    expectSitar(SitarStatus.INVALID_STATE, "") { s.markers() }
    check(s.results().all { it.errorM == null && it.errorClass == ErrorClass.UNKNOWN } && s.results().size == 6, "unknown before results")
    check(s.progress() == null, "no upload yet")
    check(s.errorAt(10 * FRAME_NS) == ErrorAt(ErrorClass.UNKNOWN, null), "no results yet")

    s.loadResults(resultsCsv())
    for (k in ERRORS.indices) {
        check(s.errorAt(10L * k * FRAME_NS) == ErrorAt(classOf(ERRORS[k]), ERRORS[k]), "errorAt sub $k")
        check(s.subtrajectoryClass(k) == classOf(ERRORS[k]), "class of sub $k")
    }
    check(s.errorAt(1000 * FRAME_NS).errorM == null, "far from any window")
    val results = s.results()
    check(results.size == ERRORS.size, "results of every sub-trajectory: $results")
    for (r in results) check(r == SubtrajectoryResult(r.subtrajectory, ERRORS[r.subtrajectory], classOf(ERRORS[r.subtrajectory])), "result $r")
    check(results.map { it.subtrajectory } == (0 until ERRORS.size).toList(), "in order")
    check(!s.resultsUnreliable(), "reliable")

    val markers = s.markers().sortedBy { it.subtrajectory }
    check(markers.map { it.subtrajectory } == listOf(1, 2, 4), "marker subs ${markers.map { it.subtrajectory }}")
    for (m in markers) {
        check(m.errorM == ERRORS[m.subtrajectory], "marker error $m")
        check(m.errorClass == classOf(ERRORS[m.subtrajectory]), "marker class $m")
        near(m.position.x, (10 * m.subtrajectory + 5) * STEP_M, "marker x")
        near(m.position.y, 1.5, "marker y")
        near(m.position.z, 2.0, "marker z")
        near(m.normal.z, -1.0, "normal faces the camera")
    }

    val plan = s.renderPlan()
    check(plan.segments.isNotEmpty(), "segments")
    for (g in plan.segments) check(g.errorClass == classOf(ERRORS[g.subtrajectory]), "segment class $g")
    check(plan.start == poseAt(0) && plan.stop == poseAt(61), "plan ends ${plan.start} ${plan.stop}")

    val tum = s.trajectoryTum()
    check(tum.lines().filter { it.isNotEmpty() }.size == 13, "13 logged poses:\n$tum")

    val folder = File(tmp, "kotlin-session").path
    s.save(folder)
    val loaded = SitarSession.load(folder)
    check(loaded.summary() == summary, "loaded summary")
    check(loaded.errorAt(40 * FRAME_NS) == ErrorAt(ErrorClass.HIGH, 0.2), "loaded results")
    loaded.close()

    s.close()
    s.close() // harmless
    expectSitar(SitarStatus.INVALID_HANDLE, "handle 0") { s.summary() }
    expectSitar(SitarStatus.INVALID_HANDLE, "handle 0") { s.frame(1, poseAt(1)) }
}

private fun errorPaths() {
    expectSitar(SitarStatus.PARSE, "") { SitarSession("{") }
    expectSitar(SitarStatus.PARSE, "bogus") { SitarSession("""{"bogus": 1}""") }
    val s = SitarSession()
    expectSitar(SitarStatus.INVALID_STATE, "start") { s.frame(FRAME_NS, poseAt(1)) }
    s.start(0, poseAt(0))
    expectSitar(SitarStatus.INVALID_ARGUMENT, "pose") { s.frame(FRAME_NS, Pose(Double.NaN, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)) }
    for (i in 1L..5L) s.frame(i * FRAME_NS, poseAt(i))
    expectSitar(SitarStatus.INVALID_ARGUMENT, "needs") { s.depth(ShortArray(W * H - 1), W, H, W * 2, K, 0) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "direct") { s.depth(ByteBuffer.allocate(W * H * 2), W, H, W * 2, K, 0) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "needs") { s.depth(ByteBuffer.allocateDirect(100), W, H, W * 2, K, 0) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "45") { s.depth(ShortArray(W * H), W, H, W * 2, K, 45) }
    // The camera image at the midpoint: both paths, the bad inputs, then its evidence.
    val luma = ByteArray(W * H) { i -> (if ((i % W) < W / 2) 40 else 200).toByte() }
    s.image(luma, W, H, W, 90)
    val lumaBuffer = ByteBuffer.allocateDirect(W * H)
    lumaBuffer.put(luma).rewind()
    s.image(lumaBuffer, W, H, W, 0)
    expectSitar(SitarStatus.INVALID_ARGUMENT, "needs") { s.image(ByteArray(W * H - 1), W, H, W, 0) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "direct") { s.image(ByteBuffer.allocate(W * H), W, H, W, 0) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "row_stride_bytes") { s.image(luma, W, H, W - 1, 0) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "display_rotation") { s.image(luma, W, H, W, 45) }
    val evidence = s.evidence(0)
    check(evidence.hasImage && evidence.thumbnailWidth >= evidence.thumbnailHeight, "$evidence")
    near(evidence.meanBrightness, 120.0, "mean brightness")
    val jpeg = s.thumbnail(0)
    check(jpeg.size > 100 && jpeg[0] == 0xFF.toByte() && jpeg[1] == 0xD8.toByte(), "thumbnail is a JPEG")
    expectSitar(SitarStatus.INVALID_ARGUMENT, "7") { s.evidence(7) }
    expectSitar(SitarStatus.PARSE, "line 2") { s.loadResults("start,error\n12,abc\n") }
    expectSitar(SitarStatus.PANIC, "on purpose") { Native.testingPanic() }
    // Still usable after the panic.
    check(s.frame(6 * FRAME_NS, poseAt(6)) == 0, "frame after a panic")
    s.close()
    expectSitar(SitarStatus.INVALID_HANDLE, "session handle") { Native.sessionFree(12345) }
}

private fun playback(tmp: File) {
    val p = PlaybackLogger("""{"convention":"arcore"}""")
    for (i in 0L until 3L) p.log(1000 + i * FRAME_NS, poseAt(i))
    check(p.size == 3L, "logged 3")
    val path = p.write(File(tmp, "logs").path, 4)
    check(path.endsWith("trajectory_4.txt"), path)
    check(File(path).readLines().size == 3, "3 lines in $path")
    p.close()
    p.close()
    expectSitar(SitarStatus.INVALID_HANDLE, "playback handle") { p.tum() }
}

private fun upload(tmp: File) {
    val s = SitarSession()
    val rec = File(tmp, "rec.mp4")
    rec.writeText("not really an mp4")
    expectSitar(SitarStatus.INVALID_ARGUMENT, "server_url") { s.upload(rec.path) }
    val closed = ServerSocket(0)
    val port = closed.localPort
    closed.close()
    val job = s.upload(rec.path, """{"server_url":"http://127.0.0.1:$port","trials":3}""")
    val deadline = System.currentTimeMillis() + 60_000
    var p = job.progress()
    while (!p.state.finished && System.currentTimeMillis() < deadline) {
        Thread.sleep(20)
        p = job.progress()
    }
    check(p.state == UploadState.FAILED && p.errorCode == SitarStatus.NETWORK.code, "upload to a closed port: $p")
    check(job.message().contains("127.0.0.1"), job.message())
    check(s.progress() == p, "session progress is the latest job's")
    job.close()
    job.close()

    val silent = ServerSocket(0)
    val job2 = s.upload(rec.path, """{"server_url":"http://127.0.0.1:${silent.localPort}","trials":3}""")
    job2.cancel()
    check(job2.progress().state == UploadState.CANCELLED, "cancelled at once")
    job2.close()
    silent.close()
    s.close()
}

private fun windowSettings(tmp: File) {
    // angle_deg: classes from the degree thresholds (2°, 4°), markers from thresholds_deg.
    val s = SitarSession("""{"convention":"unity","pose_relation":"angle_deg"}""")
    record(s)
    val degrees = doubleArrayOf(1.0, 5.0, 3.0, 0.5, 8.0, 2.5)
    s.loadResults(resultsJson(10, "angle_deg", "deg", degrees))
    val degClass = { e: Double -> if (e >= 4.0) ErrorClass.HIGH else if (e >= 2.0) ErrorClass.MEDIUM else ErrorClass.LOW }
    for (k in degrees.indices) check(s.errorAt(10L * k * FRAME_NS) == ErrorAt(degClass(degrees[k]), degrees[k]), "degrees at sub $k")
    // ≥ 4° first (subs 1, 4), then ≥ 2° (sub 2); in metres all six would pass 0.10.
    val markers = s.markers().sortedBy { it.subtrajectory }
    check(markers.map { it.subtrajectory } == listOf(1, 2, 4), "degree markers ${markers.map { it.subtrajectory }}")
    check(markers.map { it.errorClass } == listOf(ErrorClass.HIGH, ErrorClass.MEDIUM, ErrorClass.HIGH), "degree marker classes")
    check(!s.resultsUnreliable(), "a mean of 3.3° is below 8°")
    // Results that cannot be looked up here are refused, naming both values; the old ones stay.
    expectSitar(SitarStatus.INVALID_ARGUMENT, "window_frames 20") { s.loadResults(resultsJson(20, "angle_deg", "deg", degrees)) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "pose_relation trans_part") { s.loadResults(resultsCsv()) }
    check(s.errorAt(10 * FRAME_NS).errorM == 5.0, "earlier results kept")
    // Upload options must fit the session config.
    val rec = File(tmp, "window.mp4")
    rec.writeText("not really an mp4")
    expectSitar(SitarStatus.INVALID_ARGUMENT, "subtrajectory_frames 10") {
        s.upload(rec.path, """{"server_url":"http://127.0.0.1:9","window_frames":20}""")
    }
    expectSitar(SitarStatus.PARSE, "angle_rad") { s.upload(rec.path, """{"server_url":"http://127.0.0.1:9","pose_relation":"angle_rad"}""") }
    s.close()
    expectSitar(SitarStatus.PARSE, "pose_relation") { SitarSession("""{"pose_relation":"angle_rad"}""") }
    expectSitar(SitarStatus.PARSE, "medium_threshold_deg") { SitarSession("""{"medium_threshold_deg":"2"}""") }

    // 20-frame sub-trajectories take 20-frame windows.
    val long = SitarSession("""{"subtrajectory_frames":20}""")
    long.start(0, poseAt(0))
    for (i in 1L..40L) long.frame(i * FRAME_NS, poseAt(i))
    long.stop(41 * FRAME_NS, poseAt(41))
    val windows = """{"start":0,"error_m":0.02},{"start":${20 * FRAME_NS},"error_m":0.3}"""
    long.loadResults("""{"window_frames":20,"windows":[$windows]}""")
    check(long.results().map { it.errorClass } == listOf(ErrorClass.LOW, ErrorClass.HIGH), "20-frame results ${long.results()}")
    expectSitar(SitarStatus.INVALID_ARGUMENT, "subtrajectory_frames 20") { long.loadResults("""{"window_frames":10,"windows":[$windows]}""") }
    long.close()
}

/**
 * Calibrated results as the backend writes them: per window the calibrated error, its
 * interval and the raw value, keys in alphabetical order; a null upper bound leaves the window
 * without an interval.
 */
private fun calibratedJson(errors: DoubleArray, lowers: DoubleArray, uppers: Array<Double?>): String {
    val windows = errors.indices.joinToString(",") { k ->
        val start = 10L * k * FRAME_NS
        val upper = uppers[k]
        if (upper == null) """{"start":$start,"end":${start + 10 * FRAME_NS},"error_m":${errors[k]},"pairs":3,"raw_m":null,"spread_m":0.01}"""
        else """{"start":$start,"end":${start + 10 * FRAME_NS},"class":"low","error_m":${errors[k]},"lower_m":${lowers[k]},"pairs":3,"raw_m":${errors[k] / 2},"spread_m":0.01,"upper_m":$upper}"""
    }
    return """{"version":1,"setting":"trim_mean_30","trials":3,"time_unit":"ns","pose_relation":"trans_part","window_frames":10,"unit":"m","calibration":"pixel7-arcore","windows":[$windows]}"""
}

private fun calibratedResults() {
    val errors = doubleArrayOf(0.01, 0.12, 0.03, 0.015, 0.025, 0.03)
    val lowers = doubleArrayOf(0.005, 0.05, 0.01, 0.005, 0.01, 0.0)
    val uppers = arrayOf<Double?>(0.02, 0.3, 0.15, 0.12, 0.04, null)
    val json = calibratedJson(errors, lowers, uppers)
    val (low, medium, high) = Triple(ErrorClass.LOW, ErrorClass.MEDIUM, ErrorClass.HIGH)

    // classify_by "estimate" (the default): the errors colour and place markers.
    val s = SitarSession("""{"convention":"unity"}""")
    record(s)
    check(s.boundsAt(0) == null && s.resultsCalibration() == null, "no results, no bounds")
    s.loadResults(json)
    check(s.resultsCalibration() == "pixel7-arcore", "calibration ${s.resultsCalibration()}")
    for (k in 0 until 5) {
        check(s.boundsAt(10L * k * FRAME_NS) == ErrorBounds(lowers[k], uppers[k]!!, errors[k] / 2), "bounds of sub $k: ${s.boundsAt(10L * k * FRAME_NS)}")
    }
    check(s.boundsAt(50 * FRAME_NS) == null, "sub 5 has no interval")
    check(s.boundsAt(1000 * FRAME_NS) == null, "far from any window")
    check(s.results().map { it.errorClass } == listOf(low, high, low, low, low, low), "estimate classes ${s.results()}")
    // 10 cm: sub 1; 5 cm: none; 2 cm: subs 2 and 4.
    check(s.markers().map { it.subtrajectory }.sorted() == listOf(1, 2, 4), "estimate markers ${s.markers()}")

    // classify_by "upper": the upper bounds do (sub 5 has none and keeps its error).
    val cautious = SitarSession("""{"convention":"unity","classify_by":"upper"}""")
    record(cautious)
    cautious.loadResults(json)
    check(cautious.results().map { it.errorClass } == listOf(low, high, high, high, low, low), "upper classes ${cautious.results()}")
    check(cautious.errorAt(30 * FRAME_NS) == ErrorAt(high, 0.015), "error stays the estimate: ${cautious.errorAt(30 * FRAME_NS)}")
    check(cautious.subtrajectoryClass(2) == high, "sub 2 high by its upper bound")
    // 10 cm finds subs 1, 2 and 3: sub 3 gets the marker sub 4 had.
    val markers = cautious.markers().sortedBy { it.subtrajectory }
    check(markers.map { it.subtrajectory } == listOf(1, 2, 3), "upper markers $markers")
    check(markers[2].errorClass == high && markers[2].errorM == 0.015, "marker 3: ${markers[2]}")
    val plan = cautious.renderPlan()
    check(plan.segments.filter { it.subtrajectory == 3 }.all { it.errorClass == high }, "segments of sub 3 high")
    check(plan.segments.filter { it.subtrajectory == 4 }.all { it.errorClass == low }, "segments of sub 4 low")
    check(plan.segments.any { it.subtrajectory == 3 }, "sub 3 has segments")

    // Uncalibrated results replace them: no bounds, no calibration, the estimate classes.
    cautious.loadResults(resultsCsv())
    check(cautious.boundsAt(10 * FRAME_NS) == null && cautious.resultsCalibration() == null, "uncalibrated")
    check(cautious.errorAt(10 * FRAME_NS) == ErrorAt(high, 0.12), "csv class")

    // Bad bounds and a bad choice are errors naming the key.
    expectSitar(SitarStatus.PARSE, "windows[1].lower_m") { s.loadResults(json.replace("\"lower_m\":0.05", "\"lower_m\":0.5")) }
    expectSitar(SitarStatus.PARSE, "windows[0].upper_m") { s.loadResults(json.replace("\"upper_m\":0.02", "\"upper_m\":-0.02")) }
    check(s.resultsCalibration() == "pixel7-arcore", "earlier results kept")
    expectSitar(SitarStatus.PARSE, "classify_by") { SitarSession("""{"classify_by":"lower"}""") }
    s.close()
    cautious.close()
}

/** A venue map of two cells around its anchor `hall`: a low path cell and a high surface cell. */
private const val VENUE_MAP = """{"id":"v0123456789abcdef","name":"Hall","anchor":"hall","cell_m":0.25,
    "convention":"unity","unit":"m","sessions":[{"id":"s1","aligned":false,"reason":"never fully tracked"}],
    "cells":[{"center":[1.0,0.0,0.5],"kind":"path","sessions":1,"subtrajectories":2,"error_m":0.02,"class":"low","directions":[2,0,0,0,0,0,0,0]},
    {"center":[0.0,1.0,0.0],"kind":"surface","sessions":2,"subtrajectories":3,"error_m":0.3,"class":"high","directions":[0,0,3,0,0,0,0,0]}]}"""

private fun venue() {
    val s = SitarSession()
    // The image lies on the floor 2 m ahead of the start, its +X turned 90° about +Y (to −Z).
    val q = Math.sqrt(0.5)
    val image = Pose(0.0, 0.0, 2.0, 0.0, q, 0.0, q)
    expectSitar(SitarStatus.INVALID_STATE, "not recording") { s.anchor(0, "hall", image, Tracking.FULL) }
    s.start(0, poseAt(0))
    expectSitar(SitarStatus.INVALID_ARGUMENT, "anchor_id") { s.anchor(1, "", image, Tracking.FULL) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "anchor_id") { s.anchor(1, "x".repeat(65), image, Tracking.FULL) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "pose") { s.anchor(1, "hall", image.copy(px = Double.NaN), Tracking.FULL) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "tracking") { Native.sessionAnchor(1, 1, "hall", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 7).let { } }
    expectSitar(SitarStatus.INVALID_STATE, "no venue") { s.venueCells() }
    s.loadVenue(VENUE_MAP)
    expectSitar(SitarStatus.PARSE, "cells") { s.loadVenue(VENUE_MAP.replace("\"surface\"", "\"wall\"")) }
    s.anchor(1, "hall", image, Tracking.LIMITED)
    expectSitar(SitarStatus.INVALID_STATE, "full tracking") { s.venueCells() }
    s.anchor(2, "hall", image, Tracking.FULL)
    val cells = s.venueCells()
    check(cells.size == 2, "two cells $cells")
    // Venue (1, 0, 0.5) turned 90° about +Y is (0.5, 0, −1); plus the anchor at (0, 0, 2).
    near(cells[0].position.x, 0.5, "cell x", 1e-12)
    near(cells[0].position.z, 1.0, "cell z", 1e-12)
    check(cells[0].kind == CellKind.PATH && cells[0].errorClass == ErrorClass.LOW && cells[0].sessions == 1, "${cells[0]}")
    check(cells[1].kind == CellKind.SURFACE && cells[1].errorClass == ErrorClass.HIGH && cells[1].errorM == 0.3, "${cells[1]}")
    // Guide: no markers (no results), the high surface cell at (0, 1, 2) straight ahead of a
    // camera at (0, 1, 0) looking +Z, and behind one looking −Z (kept below: straight behind).
    val ahead = s.guide(Pose(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0), 60.0, 1080, 1920, 40.0)
    check(ahead.size == 1 && ahead[0].onScreen, "ahead $ahead")
    near(ahead[0].xPx, 540.0, "centre x")
    near(ahead[0].yPx, 960.0, "centre y")
    near(ahead[0].distanceM, 2.0, "distance")
    val behind = s.guide(Pose(0.3, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0), 60.0, 1080, 1920, 40.0)
    check(!behind[0].onScreen && behind[0].xPx > 540.0, "behind, to the right: $behind")
    expectSitar(SitarStatus.INVALID_ARGUMENT, "vfov_deg") { s.guide(Pose.IDENTITY, 0.0, 1080, 1920, 40.0) }
    s.close()
}

// The estimate from one walk: the calibrations are written into the temp dir by
// tests/tests/bindings_kotlin.rs (rust/ffi/tests/support/walk_calibration.rs): error =
// 0.05 m × (path + 1 mm) / 0.1 m over a 10-frame window, interval ×0.5 … ×2.
private const val WALK_FRAMES = 40L

/** x at frame [i]: 5 mm a frame for 20 frames, 3 cm for 10, 6 cm for 10 (then still). */
private fun walkX(i: Long): Double {
    val j = minOf(i, WALK_FRAMES)
    return minOf(j, 20L) * 0.005 + maxOf(minOf(j, 30L) - 20L, 0L) * 0.03 + maxOf(j - 30L, 0L) * 0.06
}

private fun walkPose(i: Long) = Pose(walkX(i), 1.5, 0.0, 0.0, 0.0, 0.0, 1.0)

/** What the calibration gives the window of 10 frames from frame [start]. */
private fun walkError(start: Long) = 0.05 * (walkX(start + 10) - walkX(start) + 0.001) / 0.1

/** Records the walk (a wall 2 m ahead at every midpoint) and stops. */
private fun walk(s: SitarSession) {
    val depth = ShortArray(16 * 16) { 2000 }
    s.start(0, walkPose(0))
    for (i in 1L..WALK_FRAMES) {
        if ((s.frame(i * FRAME_NS, walkPose(i)) and SitarSession.MIDPOINT) != 0) s.depth(depth, 16, 16, 32, Intrinsics(15.0, 15.0, 8.0, 8.0), 0)
    }
    val summary = s.stop((WALK_FRAMES + 1) * FRAME_NS, walkPose(WALK_FRAMES))
    check(summary.subtrajectories == 4 && summary.depthSamples == 4, "walk $summary")
}

private fun walkEstimate(tmp: File) {
    val calibration = File(tmp, "calibration-walk.json").readText()
    val low = ErrorClass.LOW
    val high = ErrorClass.HIGH
    val none = Provenance(ResultSource.UNKNOWN, ResultTarget.UNKNOWN, null, null)

    // Set before the walk: coloured at stop, offline, with the calibration's numbers.
    val s = SitarSession()
    check(s.resultsProvenance() == none, "no results yet: ${s.resultsProvenance()}")
    s.setCalibration(calibration)
    walk(s)
    val results = s.results()
    check(results.map { it.errorClass } == listOf(low, low, high, high), "walk classes $results")
    for (r in results) near(r.errorM!!, walkError(10L * r.subtrajectory), "walk error of sub ${r.subtrajectory}", 1e-12)
    val fromWalk = s.resultsProvenance()
    check(fromWalk == Provenance(ResultSource.WALK, ResultTarget.LIVE, 1, true) && !fromWalk.isGuess, "from the walk: $fromWalk")
    check(s.resultsCalibration() == "on_device", "calibration ${s.resultsCalibration()}")
    val bounds = s.boundsAt(20 * FRAME_NS)
    check(bounds != null, "the walk's windows have intervals")
    near(bounds!!.upperM, 2 * walkError(20), "upper bound", 1e-12)
    val markers = s.markers()
    // In time order: sub 2 is the first high place; sub 3 and the low ones lie within 0.5 m of it.
    check(markers.size == 1 && markers[0].subtrajectory == 2 && markers[0].errorClass == high, "walk markers $markers")
    // The backend's results replace the walk's.
    s.loadResults("start,error\n0,0.2\n${10 * FRAME_NS},0.01\n${20 * FRAME_NS},0.01\n${30 * FRAME_NS},0.01\n")
    check(s.results().map { it.errorClass } == listOf(high, low, low, low), "backend classes ${s.results()}")
    check(s.resultsProvenance() == none && s.resultsCalibration() == null, "legacy CSV says nothing of its source")
    // A calibration given now keeps them.
    s.setCalibration(calibration)
    check(s.results().map { it.errorClass } == listOf(high, low, low, low), "backend results kept")
    s.close()
    expectSitar(SitarStatus.INVALID_HANDLE, "handle 0") { s.setCalibration(calibration) }
    expectSitar(SitarStatus.INVALID_HANDLE, "handle 0") { s.resultsProvenance() }

    // Set after the stop: coloured at once; a calibration whose runs do not predict the error says so.
    val later = SitarSession()
    walk(later)
    check(later.results().all { it.errorClass == ErrorClass.UNKNOWN }, "uncoloured without a calibration")
    later.setCalibration(File(tmp, "calibration-guess.json").readText())
    check(later.results().map { it.errorClass } == listOf(low, low, high, high), "coloured at once")
    val guess = later.resultsProvenance()
    check(guess.source == ResultSource.WALK && guess.informative == false && guess.isGuess, "a guess: $guess")
    later.close()

    // Refused calibrations name what is wrong and change nothing.
    val refused = SitarSession()
    expectSitar(SitarStatus.PARSE, "not a calibration file") { refused.setCalibration("{") }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "20 window frames") { refused.setCalibration(File(tmp, "calibration-window20.json").readText()) }
    expectSitar(SitarStatus.INVALID_ARGUMENT, "no model for the live error from 1 run") {
        refused.setCalibration(File(tmp, "calibration-expected-only.json").readText())
    }
    walk(refused)
    check(refused.results().all { it.errorClass == ErrorClass.UNKNOWN } && refused.resultsProvenance() == none, "nothing taken")
    refused.close()
}

fun main(args: Array<String>) {
    val tmp = File(args[1])
    check(SitarSession.version() == args[0], "version ${SitarSession.version()}")
    // `Sitar.init(context)`'s entry point: on the host a no-op, as the platform verifier is
    // always in use there; any object reaches it (only Android needs a Context).
    check(Native.platformTlsInit(Any()), "platformTlsInit on the host")
    check(Native.platformTlsInit("again"), "platformTlsInit twice")
    try {
        Native::class.java.getMethod("platformTlsInit", Any::class.java).invoke(null, null)
        check(false, "platformTlsInit(null) should throw")
    } catch (e: java.lang.reflect.InvocationTargetException) {
        val cause = e.cause
        check(cause is SitarException && cause.status == SitarStatus.NULL && (cause.message ?: "").contains("context"), "platformTlsInit(null): $cause")
    }
    wholeSession(tmp)
    errorPaths()
    playback(tmp)
    upload(tmp)
    windowSettings(tmp)
    calibratedResults()
    venue()
    walkEstimate(tmp)
    println("PASSED $checks checks")
}
