package io.github.sitar.recorder

import io.github.sitar.CellKind
import io.github.sitar.ErrorClass
import io.github.sitar.Pose
import io.github.sitar.Tracking
import io.github.sitar.SitarSession

// Host test of the recorder sample's logic (RecorderFlow, Json, DepthInput) on
// the JVM, with a real libsitar session behind the flow's actions; run by
// tests/tests/kotlin_apps.rs. Prints "PASSED n checks", then one
// "JSON <hex of the input> <document>" line per escaping case, which the Rust
// side parses with serde_json.

private var checks = 0

private fun check(condition: Boolean, what: String) {
    checks++
    if (!condition) throw AssertionError("check failed: $what")
}

private const val FRAME_NS = 33_333_333L

private fun pose(i: Int) = Pose(0.05 * i, 1.4, 0.0, 0.0, 0.0, 0.0, 1.0)

/** Plays [flow]'s actions on a real session as the Activity does; returns the session's stop summary frames. */
private class Recorder {
    var session: SitarSession? = null
    var stops = 0
    var stoppedAt = 0L
    var reason: StopReason? = null
    var frames = 0

    fun apply(a: Action) {
        when (a) {
            is Action.Start -> {
                session = SitarSession(Json.obj("convention" to "arcore", "server_url" to "http://127.0.0.1:9/"))
                session!!.start(a.tNs, a.pose)
            }
            is Action.Frame -> session!!.frame(a.tNs, a.pose)
            is Action.Stop -> {
                frames = session!!.stop(a.tNs, a.pose).frames
                stops++
                stoppedAt = a.tNs
                reason = a.reason
            }
            Action.None -> Unit
        }
    }
}

private fun startAndStopWithTheButtons() {
    val flow = RecorderFlow()
    val rec = Recorder()
    check(!flow.pressStop(), "Stop does nothing before a recording")
    rec.apply(flow.onFrame(1 * FRAME_NS, pose(1), tracking = true))
    check(rec.session == null, "no recording before Start")
    check(flow.pressStart(), "Start")
    check(!flow.pressStart(), "a second Start does nothing")
    // Untracked frames neither start nor count.
    rec.apply(flow.onFrame(2 * FRAME_NS, pose(2), tracking = false))
    check(flow.state == RecorderFlow.State.STARTING, "still starting while not tracking")
    for (i in 3..33) rec.apply(flow.onFrame(i * FRAME_NS, pose(i), tracking = i != 20))
    check(flow.state == RecorderFlow.State.RECORDING, "recording")
    check(flow.pressStop(), "Stop")
    rec.apply(flow.onFrame(34 * FRAME_NS, pose(34), tracking = true))
    check(rec.stops == 1 && rec.reason == StopReason.BUTTON && rec.stoppedAt == 34 * FRAME_NS, "stopped at the frame after Stop")
    // Frames 4…33 without the untracked 20th: 29 frames (start and stop are not frames).
    check(rec.frames == 29, "29 frames recorded: ${rec.frames}")
    check(flow.state == RecorderFlow.State.IDLE && flow.message.contains("uploading"), flow.message)
    rec.session!!.close()
}

private fun aPauseEndsTheRecordingCleanly() {
    val flow = RecorderFlow()
    val rec = Recorder()
    flow.pressStart()
    for (i in 1..25) rec.apply(flow.onFrame(i * FRAME_NS, pose(i), tracking = true))
    // ARCore hands the last frame out again: not a new frame.
    rec.apply(flow.onFrame(25 * FRAME_NS, pose(25), tracking = true))
    val stop = flow.onPause()
    check(stop is Action.Stop && stop.reason == StopReason.PAUSE, "a pause stops: $stop")
    check((stop as Action.Stop).tNs == 25 * FRAME_NS, "at the last frame: ${stop.tNs}")
    rec.apply(stop)
    check(rec.frames == 24, "frames 2…25 recorded: ${rec.frames}")
    check(flow.message.contains("paused") && flow.message.contains("ended"), "the status says so: ${flow.message}")
    check(flow.state == RecorderFlow.State.IDLE, "idle after the pause")
    // Frames after the pause (the resumed app) record nothing until Start.
    rec.apply(flow.onFrame(40 * FRAME_NS, pose(40), tracking = true))
    check(rec.stops == 1, "one stop only")
    check(flow.onPause() == Action.None, "a second pause does nothing")
    // A pause between Start and the first tracked frame calls the recording off.
    flow.pressStart()
    check(flow.onPause() == Action.None && flow.state == RecorderFlow.State.IDLE, "a pending start is called off")
    check(flow.message.contains("before the recording started"), flow.message)
    // A pause while Stop waits for its frame stops at the last frame too.
    flow.pressStart()
    for (i in 50..60) rec.apply(flow.onFrame(i * FRAME_NS, pose(i), tracking = true))
    flow.pressStop()
    val late = flow.onPause()
    check(late is Action.Stop && late.tNs == 60 * FRAME_NS && late.reason == StopReason.PAUSE, "pending stop: $late")
    rec.apply(late)
    rec.session!!.close()
}

private fun depthInputs() {
    check(displayRotationDeg(90, 0) == 90, "portrait, sensor 90")
    check(displayRotationDeg(90, 1) == 0, "landscape (ROTATION_90)")
    check(displayRotationDeg(90, 2) == 270, "upside down")
    check(displayRotationDeg(90, 3) == 180, "landscape (ROTATION_270)")
    check(displayRotationDeg(270, 0) == 270, "sensor 270")
    check(displayRotationDeg(0, 3) == 90, "sensor 0")
    try {
        displayRotationDeg(90, 4)
        check(false, "rotation 4 is refused")
    } catch (e: IllegalArgumentException) {
        check((e.message ?: "").contains("surface rotation 4"), "${e.message}")
    }
    val k = depthIntrinsics(floatArrayOf(480f, 481f), floatArrayOf(320f, 240f), 640, 480, 160, 120)
    check(k.fx == 120.0 && k.fy == 120.25 && k.cx == 80.0 && k.cy == 60.0, "scaled intrinsics: $k")
}

/** Escaping cases: printed for serde_json, and fed to the library, which must parse them. */
private val JSON_CASES = listOf(
    "http://192.168.0.10:8000",
    "http://h/\"quoted\"",
    "back\\slash\\",
    "line\nbreak\r\ttab",
    "\u0000\u0001\u001f control",
    "ünïcödé ✓ \u2028 separators \u2029",
    "{\"injected\":true}"
)

private fun hex(s: String): String = s.toByteArray(Charsets.UTF_8).joinToString("") { String.format("%02x", it) }

private fun json() {
    for (url in JSON_CASES) {
        val doc = Json.obj("convention" to "arcore", "server_url" to url)
        // The library's config parser (serde_json) takes every one of them.
        SitarSession(doc).close()
        println("JSON ${hex(url)} $doc")
    }
    val options = Json.obj("trials" to 10, "setting" to "trim_mean_30", "big" to 12345678901L, "x" to 0.5, "ok" to true)
    check(options == """{"trials":10,"setting":"trim_mean_30","big":12345678901,"x":0.5,"ok":true}""", options)
    try {
        Json.obj("x" to Double.NaN)
        check(false, "NaN is refused")
    } catch (e: IllegalArgumentException) {
        check((e.message ?: "").contains("field x"), "${e.message}")
    }
}

/** The venue logic with a real session: tracking states, edge arrows from its guide, the kineticon, the colours. */
private fun venue() {
    check(VenueAnchor.tracking(tracking = true, paused = false, fullTracking = true) == Tracking.FULL, "tracked image: full")
    check(VenueAnchor.tracking(tracking = true, paused = false, fullTracking = false) == Tracking.LIMITED, "last known pose: limited")
    check(VenueAnchor.tracking(tracking = false, paused = true, fullTracking = false) == Tracking.LIMITED, "paused: limited")
    check(VenueAnchor.tracking(tracking = false, paused = false, fullTracking = false) == Tracking.NONE, "stopped: none")

    // ARCore convention: the camera looks along −Z. A high surface cell 2 m ahead of the anchor's
    // centre and one 3 m to its right.
    val map = """{"id":"v0123456789abcdef","name":"Hall","anchor":"${VenueAnchor.ID}","cell_m":0.25,
        "convention":"arcore","unit":"m","sessions":[],"cells":[
        {"center":[0.0,1.0,0.0],"kind":"surface","sessions":2,"subtrajectories":3,"error_m":0.3,"class":"high","directions":[0,0,3,0,0,0,0,0]},
        {"center":[3.0,1.0,0.0],"kind":"surface","sessions":2,"subtrajectories":3,"error_m":0.2,"class":"high","directions":[0,0,3,0,0,0,0,0]}]}"""
    val s = SitarSession(Json.obj("convention" to "arcore"))
    s.start(0, Pose.IDENTITY)
    s.loadVenue(map)
    s.anchor(1, VenueAnchor.ID, Pose(0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 1.0), VenueAnchor.tracking(tracking = true, paused = false, fullTracking = true))
    val guides = s.guide(Pose(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0), 60.0, 1080, 1920, 40.0)
    check(guides.size == 2 && guides[0].onScreen && !guides[1].onScreen, "one cell ahead, one out of view: $guides")
    val arrows = VenueView.edgeArrows(guides)
    check(arrows.size == 1 && arrows[0].index == 1, "one arrow: $arrows")
    check(Math.abs(arrows[0].x - 1040f) < 1e-3 && Math.abs(arrows[0].y - 960f) < 1e-3 && arrows[0].rotationDeg == 0f, "right edge, pointing right: ${arrows[0]}")
    // Above and behind (camera turned around, 5 m below): the arrow points up, −90° clockwise.
    val up = VenueView.edgeArrows(s.guide(Pose(0.0, -5.0, 0.0, 0.0, 1.0, 0.0, 0.0), 60.0, 1080, 1920, 40.0))
    check(up.size == 2 && Math.abs(up[0].rotationDeg + 90f) < 1e-3 && up[0].y < 960f, "up and behind: $up")
    s.close()

    val k = Kineticon(pulseSeconds = 3.0, pulsesPerSecond = 1.5, amplitude = 0.4)
    check(k.scale(1, false, 5.0) == 1.0, "unseen: still")
    check(k.scale(1, true, 5.0) == 1.0 && k.scale(1, true, 5.0 + 1.0 / 3) > 1.3, "first seen: pulses")
    check(k.scale(1, true, 8.01) == 1.0, "after its first seconds: still")
    k.reset()
    check(k.scale(1, true, 9.0) == 1.0 && k.scale(1, true, 9.0 + 1.0 / 3) > 1.3, "reset: pulses again")

    val tile = VenueView.cellColor(CellKind.SURFACE, ErrorClass.HIGH)
    val trail = VenueView.cellColor(CellKind.PATH, ErrorClass.HIGH)
    check(tile[0] > 0.8f && tile[3] in 0.3f..0.9f && trail[3] < tile[3], "translucent red tile, fainter trail")
}

fun main() {
    startAndStopWithTheButtons()
    aPauseEndsTheRecordingCleanly()
    depthInputs()
    json()
    venue()
    println("PASSED $checks checks")
}
