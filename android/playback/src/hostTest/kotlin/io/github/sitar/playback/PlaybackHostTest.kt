package io.github.sitar.playback

import io.github.sitar.Pose
import java.io.File

// Host test of the playback app's logic (PlaybackRun, PlaybackRequest, StatusFile)
// on the JVM with the real libsitar playback logger (LibraryTrialLog through JNI),
// run by tests/tests/kotlin_apps.rs. Args: <temp dir>. Prints "PASSED n checks".

private var checks = 0

private fun check(condition: Boolean, what: String) {
    checks++
    if (!condition) throw AssertionError("check failed: $what")
}

private const val FRAME_NS = 33_333_333L

private fun pose(i: Int) = Pose(0.01 * i, 1.5, -0.02 * i, 0.0, 0.0, 0.0, 1.0)

/** The extras of an `am start` (or none, for a launch by hand). */
private class FakeExtras(private val ints: Map<String, Int>, private val strings: Map<String, String>) : Extras {
    override fun int(name: String, default: Int): Int = ints[name] ?: default
    override fun string(name: String): String? = strings[name]
}

private fun request(files: File, trials: Int, first: Int, out: String = "out"): PlaybackRequest {
    val extras = FakeExtras(
        mapOf(PlaybackRequest.EXTRA_TRIALS to trials, PlaybackRequest.EXTRA_FIRST to first),
        mapOf(
            PlaybackRequest.EXTRA_RECORDING to File(files, PlaybackRequest.RECORDING_FILE).path,
            PlaybackRequest.EXTRA_OUTPUT to File(files, out).path
        )
    )
    return PlaybackRequest.from(extras, files)
}

private fun status(dir: File): String = File(dir, PlaybackRequest.STATUS_FILE).readText()

/** Starts the dataset of [step] as the Activity does, then feeds [frames] frames and a FINISHED. */
private fun playTrial(run: PlaybackRun, step: Step, frames: Int, t0: Long = 1_000_000_000L): Step {
    check(step is Step.Play, "a Play step, got $step")
    run.started((step as Step.Play).token)
    for (i in 0 until frames) {
        val s = run.onFrame(t0 + i * FRAME_NS, pose(i), Playback.OK)
        check(s == Step.Wait, "frames ask for nothing: $s")
    }
    return run.onFrame(t0 + frames * FRAME_NS, pose(frames), Playback.FINISHED)
}

/** TUM lines of a written trajectory; each line `t x y z qx qy qz qw`, t integer ns. */
private fun tumLines(file: File): List<String> {
    check(file.isFile, "$file exists")
    val lines = file.readLines().filter { it.isNotBlank() }
    for (l in lines) {
        val cols = l.trim().split(Regex("\\s+"))
        check(cols.size == 8, "8 columns in '$l'")
        check(cols[0].toLongOrNull() != null, "integer nanoseconds in '$l'")
    }
    return lines
}

private fun noPartFiles(dir: File) {
    val names = dir.list()!!.toList()
    check(names.none { it.endsWith(".part") }, "no half-written file left in $dir: $names")
}

private fun launchesAndWritesEveryTrial(work: File) {
    val files = File(work, "normal").apply { mkdirs() }
    File(files, PlaybackRequest.RECORDING_FILE).writeText("mp4")
    val run = PlaybackRun { LibraryTrialLog() }
    val r = request(files, trials = 3, first = 4)
    check(run.launch(r) == Step.Wait, "a launch before onResume waits")
    check(status(r.output) == "starting\n", "status starting: ${status(r.output)}")
    var step = run.onResume()
    check(status(r.output) == "playing 1/3\n", "status playing 1/3")
    // Frames before ARCore confirmed the dataset belong to the old one: ignored.
    check(run.onFrame(5, pose(0), Playback.FINISHED) == Step.Wait, "no trial ends before it started")
    for (k in 0 until 3) {
        step = playTrial(run, step, frames = 20 + k)
        if (k < 2) check(status(r.output) == "playing ${k + 2}/3\n", "status after trial $k: ${status(r.output)}")
    }
    check(step == Step.Done(3), "done after three trials: $step")
    check(status(r.output) == "done 3/3\n", "status done")
    for (k in 0 until 3) {
        val lines = tumLines(File(r.output, "trajectory_${4 + k}.txt"))
        check(lines.size == 20 + k, "trial $k has its ${20 + k} frames: ${lines.size}")
        check(lines[0].startsWith("1000000000 "), "first stamp of trial $k: ${lines[0]}")
    }
    check(!File(r.output, "trajectory_3.txt").exists() && !File(r.output, "trajectory_7.txt").exists(), "only trajectories 4…6")
    noPartFiles(r.output)
    // After the run, frames and resumes change nothing.
    check(run.onResume() == Step.Wait, "nothing to resume after done")
    run.close()
}

private fun pauseDropsTheUnfinishedTrial(work: File) {
    val files = File(work, "pause").apply { mkdirs() }
    File(files, PlaybackRequest.RECORDING_FILE).writeText("mp4")
    val run = PlaybackRun { LibraryTrialLog() }
    val r = request(files, trials = 2, first = 0)
    run.onResume()
    val step = run.launch(r)
    check(step is Step.Play && step.trial == 0, "a launch while resumed plays at once: $step")
    run.started((step as Step.Play).token)
    for (i in 0 until 10) run.onFrame(2_000_000_000L + i * FRAME_NS, pose(i), Playback.OK)
    run.onPause()
    check(status(r.output) == "paused 1/2\n", "status paused: ${status(r.output)}")
    check(!run.isCurrent(step.token), "a Play step from before the pause is stale")
    // Frames after the pause (the GL thread's last ones) are not logged.
    check(run.onFrame(3_000_000_000L, pose(0), Playback.FINISHED) == Step.Wait, "no trial ends while paused")
    check(!File(r.output, "trajectory_0.txt").exists(), "the dropped trial is not written")
    val again = run.onResume()
    check(again is Step.Play && again.trial == 0 && again.token != step.token, "the same trial starts again: $again")
    check(run.isCurrent((again as Step.Play).token), "the new step is current")
    var next = playTrial(run, again, frames = 15)
    check(tumLines(File(r.output, "trajectory_0.txt")).size == 15, "trial 0 holds only the replay after the resume")
    next = playTrial(run, next, frames = 12)
    check(next == Step.Done(2), "done: $next")
    noPartFiles(r.output)
    run.close()
}

private fun secondLaunchReplacesTheRunningOne(work: File) {
    val files = File(work, "second").apply { mkdirs() }
    File(files, PlaybackRequest.RECORDING_FILE).writeText("mp4")
    val run = PlaybackRun { LibraryTrialLog() }
    run.onResume()
    val a = request(files, trials = 3, first = 0, out = "a")
    var step = run.launch(a)
    step = playTrial(run, step, frames = 8)
    check(step is Step.Play && step.trial == 1, "trial 2 of A starts: $step")
    val stale = (step as Step.Play).token
    run.started(stale)
    run.onFrame(1_000_000_000L, pose(0), Playback.OK)
    // onNewIntent with another request while A plays its second trial.
    val b = request(files, trials = 1, first = 7, out = "b")
    val playB = run.launch(b)
    check(playB is Step.Play && playB.trial == 0 && playB.of == 1, "B starts at once: $playB")
    check(status(a.output) == "failed superseded by a new launch\n", "A's folder says why it stopped: ${status(a.output)}")
    check(!run.isCurrent(stale), "A's step is stale")
    run.started(stale) // a late confirmation of A's dataset changes nothing
    check(run.onFrame(1_100_000_000L, pose(1), Playback.FINISHED) == Step.Wait, "B's trial has not started yet")
    val done = playTrial(run, playB, frames = 5)
    check(done == Step.Done(1), "B is done: $done")
    check(tumLines(File(b.output, "trajectory_7.txt")).size == 5, "B's trial is trajectory_7")
    check(File(a.output, "trajectory_0.txt").isFile && !File(a.output, "trajectory_1.txt").exists(), "A kept its finished trial only")
    run.close()
}

private fun failuresReachTheStatusFile(work: File) {
    val files = File(work, "fail").apply { mkdirs() }
    val run = PlaybackRun { LibraryTrialLog() }
    run.onResume()
    // The recording was not pushed.
    val missing = request(files, trials = 2, first = 0)
    val step = run.launch(missing)
    check(step is Step.Failed && step.message.contains("cannot read the recording"), "missing recording: $step")
    check(status(missing.output).startsWith("failed cannot read the recording ${missing.recording}"), status(missing.output))
    // ARCore stops with IO_ERROR in the middle of a trial.
    File(files, PlaybackRequest.RECORDING_FILE).writeText("mp4")
    val play = run.launch(missing)
    run.started((play as Step.Play).token)
    run.onFrame(10, pose(0), Playback.OK)
    val io = run.onFrame(20, pose(1), Playback.IO_ERROR)
    check(io is Step.Failed, "IO_ERROR ends the run: $io")
    check(status(missing.output).startsWith("failed ARCore stopped playing") && status(missing.output).contains("trial 1/2"), status(missing.output))
    // A trial with no frame at all.
    val empty = run.launch(missing)
    run.started((empty as Step.Play).token)
    val none = run.onFrame(30, pose(0), Playback.FINISHED)
    check(none is Step.Failed && none.message.contains("gave no frame"), "no frame: $none")
    // A message over several lines stays on the status line.
    run.launch(missing)
    run.fail("ARCore cannot play it:\nPlaybackFailedException")
    check(status(missing.output) == "failed ARCore cannot play it: PlaybackFailedException\n", status(missing.output))
    // Bad extras are refused, naming the extra, into the output folder.
    val bad = FakeExtras(mapOf(PlaybackRequest.EXTRA_TRIALS to 0), emptyMap())
    try {
        PlaybackRequest.from(bad, files)
        check(false, "trials = 0 is refused")
    } catch (e: IllegalArgumentException) {
        check((e.message ?: "").contains("extra trials = 0"), "the message names the extra: ${e.message}")
        run.refuse(File(files, "out"), e.message!!)
        check(status(File(files, "out")).startsWith("failed extra trials = 0"), status(File(files, "out")))
    }
    try {
        PlaybackRequest.from(FakeExtras(mapOf(PlaybackRequest.EXTRA_FIRST to -1), emptyMap()), files)
        check(false, "first = -1 is refused")
    } catch (e: IllegalArgumentException) {
        check((e.message ?: "").contains("extra first = -1"), "${e.message}")
    }
    // Duplicate frames (ARCore repeats a frame without a new camera image) are skipped.
    val dup = run.launch(missing)
    run.started((dup as Step.Play).token)
    for (t in longArrayOf(100, 100, 200, 150, 300)) run.onFrame(t, pose(0), Playback.OK)
    val last = run.onFrame(400, pose(0), Playback.FINISHED)
    check(tumLines(File(missing.output, "trajectory_0.txt")).size == 3, "three distinct increasing stamps logged")
    check(last is Step.Play, "then trial 2: $last")
    run.close()
}

private fun defaultsOfALaunchByHand(work: File) {
    val files = File(work, "byhand")
    val r = PlaybackRequest.from(FakeExtras(emptyMap(), emptyMap()), files)
    check(r.trials == PlaybackRequest.DEFAULT_TRIALS && r.first == 0, "defaults: $r")
    check(r.recording == File(files, "recording.mp4") && r.output == File(files, "out"), "default files: $r")
    check(r.trajectoryName(2) == "trajectory_2.txt", r.trajectoryName(2))
    // Status writes are whole: the partial name never stays.
    val s = StatusFile(File(work, "status-dir/status.txt"))
    s.starting()
    s.playing(0, 5)
    check(File(work, "status-dir/status.txt").readText() == "playing 1/5\n", "replaced in place")
    check(File(work, "status-dir").list()!!.toList() == listOf("status.txt"), "only status.txt")
}

fun main(args: Array<String>) {
    val work = File(args[0])
    launchesAndWritesEveryTrial(work)
    pauseDropsTheUnfinishedTrial(work)
    secondLaunchReplacesTheRunningOne(work)
    failuresReachTheStatusFile(work)
    defaultsOfALaunchByHand(work)
    println("PASSED $checks checks")
}
