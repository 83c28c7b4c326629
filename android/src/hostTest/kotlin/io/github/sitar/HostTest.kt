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

private fun expectSitar(code: Int, needle: String, block: () -> Unit) {
    try {
        block()
    } catch (e: SitarException) {
        check(e.code == code, "expected code $code, got ${e.code}: ${e.message}")
        check((e.message ?: "").contains(needle), "message '${e.message}' should mention '$needle'")
        return
    }
    throw AssertionError("expected SitarException($code) mentioning '$needle'")
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

    expectSitar(SitarException.INVALID_STATE, "") { s.markers() }
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
    expectSitar(SitarException.INVALID_HANDLE, "handle 0") { s.summary() }
    expectSitar(SitarException.INVALID_HANDLE, "handle 0") { s.frame(1, poseAt(1)) }
}

private fun errorPaths() {
    expectSitar(SitarException.PARSE, "") { SitarSession("{") }
    expectSitar(SitarException.PARSE, "bogus") { SitarSession("""{"bogus": 1}""") }
    val s = SitarSession()
    expectSitar(SitarException.INVALID_STATE, "start") { s.frame(FRAME_NS, poseAt(1)) }
    s.start(0, poseAt(0))
    expectSitar(SitarException.INVALID_ARGUMENT, "pose") { s.frame(FRAME_NS, Pose(Double.NaN, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)) }
    for (i in 1L..5L) s.frame(i * FRAME_NS, poseAt(i))
    expectSitar(SitarException.INVALID_ARGUMENT, "needs") { s.depth(ShortArray(W * H - 1), W, H, W * 2, K, 0) }
    expectSitar(SitarException.INVALID_ARGUMENT, "direct") { s.depth(ByteBuffer.allocate(W * H * 2), W, H, W * 2, K, 0) }
    expectSitar(SitarException.INVALID_ARGUMENT, "needs") { s.depth(ByteBuffer.allocateDirect(100), W, H, W * 2, K, 0) }
    expectSitar(SitarException.INVALID_ARGUMENT, "45") { s.depth(ShortArray(W * H), W, H, W * 2, K, 45) }
    expectSitar(SitarException.PARSE, "line 2") { s.loadResults("start,error\n12,abc\n") }
    expectSitar(SitarException.PANIC, "on purpose") { Native.testingPanic() }
    // Still usable after the panic.
    check(s.frame(6 * FRAME_NS, poseAt(6)) == 0, "frame after a panic")
    s.close()
    expectSitar(SitarException.INVALID_HANDLE, "session handle") { Native.sessionFree(12345) }
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
    expectSitar(SitarException.INVALID_HANDLE, "playback handle") { p.tum() }
}

private fun upload(tmp: File) {
    val s = SitarSession()
    val rec = File(tmp, "rec.mp4")
    rec.writeText("not really an mp4")
    expectSitar(SitarException.INVALID_ARGUMENT, "server_url") { s.upload(rec.path) }
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
    check(p.state == UploadState.FAILED && p.errorCode == SitarException.NETWORK, "upload to a closed port: $p")
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

fun main(args: Array<String>) {
    val tmp = File(args[1])
    check(SitarSession.version() == args[0], "version ${SitarSession.version()}")
    wholeSession(tmp)
    errorPaths()
    playback(tmp)
    upload(tmp)
    println("PASSED $checks checks")
}
