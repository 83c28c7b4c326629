package io.github.sitar.playback

import io.github.sitar.Pose
import java.io.File

/** ARCore's `PlaybackStatus`, without Android. */
enum class Playback { NONE, OK, IO_ERROR, FINISHED }

/** One trial's pose log: the library's `PlaybackLogger` in the app. */
interface TrialLog {
    /** Logs a frame's pose (timestamps strictly increase). */
    fun log(tNs: Long, pose: Pose)

    /** The number of logged frames. */
    val size: Long

    /** Writes `dir/trajectory_<index>.txt` whole (temp name, then rename). */
    fun write(dir: String, index: Int)

    /** Frees it. */
    fun close()
}

/** What the Activity does next. */
sealed class Step {
    /** Nothing to do. */
    object Wait : Step()

    /**
     * Start trial [trial] of [of]: pause the ARCore session, set [recording] as the
     * playback dataset, resume, then call [PlaybackRun.started] with [token]
     * (or [PlaybackRun.fail] if ARCore refused).
     */
    data class Play(val recording: File, val trial: Int, val of: Int, val token: Long) : Step()

    /** Every trial was written. */
    data class Done(val trials: Int) : Step()

    /** The run ended with [message], which is in the status file too. */
    data class Failed(val message: String) : Step()
}

/**
 * The playback app's logic, free of Android (tested on the JVM): launches, the
 * Activity's pause and resume, every camera frame, the trajectory and status files.
 *
 * - A launch (first start or `onNewIntent`) replaces whatever was running: the
 *   unfinished trial is dropped and the old folder's status says so.
 * - A pause (another app, the screen went off) drops the unfinished trial: ARCore
 *   does not replay the frames it skipped while paused, so that trial would not
 *   be a replay of the recording. It restarts from the beginning on resume.
 * - Each finished trial is written as `trajectory_{first + k}.txt` at once.
 *
 * Thread-safe: the Activity calls it from the UI and the GL thread.
 */
class PlaybackRun(private val newLog: () -> TrialLog) {
    private var request: PlaybackRequest? = null
    private var status: StatusFile? = null
    private var trial = 0
    private var log: TrialLog? = null
    private var lastT = Long.MIN_VALUE
    private var resumed = false
    /** Numbers the [Step.Play]s: until [started] confirms the latest, frames belong to the old dataset. */
    private var token = 0L

    /** What the screen shows. */
    @get:Synchronized
    val line: String
        get() = status?.line ?: "waiting for a launch"

    /** A launch of the app with [next] (the extras of `onCreate` or `onNewIntent`). */
    @Synchronized
    fun launch(next: PlaybackRequest): Step {
        val previous = request
        // An unfinished run elsewhere says why it stops; in the same folder the new status replaces it.
        if (previous != null && previous.output.absoluteFile != next.output.absoluteFile) {
            report { it.failed("superseded by a new launch") }
        }
        dropTrial()
        request = next
        trial = 0
        status = StatusFile(File(next.output, PlaybackRequest.STATUS_FILE))
        if (!next.output.isDirectory && !next.output.mkdirs()) {
            return end("cannot create the output folder ${next.output}")
        }
        if (!next.recording.canRead()) {
            return end("cannot read the recording ${next.recording}")
        }
        report { it.starting() }
        return if (resumed) begin() else Step.Wait
    }

    /** A launch whose extras were refused: reported in [output]'s status file. */
    @Synchronized
    fun refuse(output: File, message: String): Step {
        dropTrial()
        request = null
        status = StatusFile(File(output, PlaybackRequest.STATUS_FILE))
        return end(message)
    }

    /** The Activity resumed: the unfinished trial (if any) starts (again). */
    @Synchronized
    fun onResume(): Step {
        resumed = true
        return if (request != null) begin() else Step.Wait
    }

    /** The Activity paused: the unfinished trial is dropped. */
    @Synchronized
    fun onPause() {
        resumed = false
        val r = request ?: return
        dropTrial()
        report { it.paused(trial, r.trials) }
    }

    /** ARCore plays the dataset of the [Step.Play] with [token]. */
    @Synchronized
    fun started(token: Long) {
        if (token != this.token || request == null) return
        lastT = Long.MIN_VALUE
        log?.close()
        log = newLog()
    }

    /** One camera frame: its timestamp, display-oriented pose and ARCore's playback status. */
    @Synchronized
    fun onFrame(tNs: Long, pose: Pose, playback: Playback): Step {
        val r = request ?: return Step.Wait
        val current = log ?: return Step.Wait
        return when (playback) {
            Playback.NONE -> Step.Wait
            Playback.OK -> {
                // ARCore hands out the same frame again when no new camera image arrived.
                if (tNs > lastT) {
                    current.log(tNs, pose)
                    lastT = tNs
                }
                Step.Wait
            }
            Playback.IO_ERROR -> end("ARCore stopped playing ${r.recording} with IO_ERROR in trial ${trial + 1}/${r.trials}")
            Playback.FINISHED -> finishTrial(r, current)
        }
    }

    /** Whether [token] is the latest [Step.Play] of a resumed, running launch. */
    @Synchronized
    fun isCurrent(token: Long): Boolean = token == this.token && resumed && request != null

    /** ARCore or the app failed: the run ends with [message]. */
    @Synchronized
    fun fail(message: String): Step = end(message)

    /** Frees the open log. */
    @Synchronized
    fun close() {
        dropTrial()
    }

    private fun finishTrial(r: PlaybackRequest, current: TrialLog): Step {
        if (current.size == 0L) {
            return end("ARCore played ${r.recording} but gave no frame in trial ${trial + 1}/${r.trials}")
        }
        try {
            current.write(r.output.path, r.first + trial)
        } catch (e: Exception) {
            return end("cannot write ${r.trajectoryName(trial)} into ${r.output}: ${e.message}")
        }
        dropTrial()
        trial++
        if (trial < r.trials) return begin()
        report { it.done(r.trials) }
        request = null
        return Step.Done(r.trials)
    }

    private fun begin(): Step {
        val r = request ?: return Step.Wait
        dropTrial()
        token++
        report { it.playing(trial, r.trials) }
        return Step.Play(r.recording, trial, r.trials, token)
    }

    private fun dropTrial() {
        log?.close()
        log = null
    }

    private fun end(message: String): Step {
        dropTrial()
        request = null
        report { it.failed(message) }
        return Step.Failed(message)
    }

    /** Writes the status; a folder that cannot be written is on the screen still ([line]). */
    private fun report(write: (StatusFile) -> Unit) {
        val s = status ?: return
        try {
            write(s)
        } catch (e: java.io.IOException) {
            // Nothing else to tell: the status file is how the backend hears of problems.
        }
    }
}
