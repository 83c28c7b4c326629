package io.github.sitar.recorder

import io.github.sitar.Pose

/** Why a recording ended. */
enum class StopReason { BUTTON, PAUSE }

/** What the Activity does with a camera frame or a pause. */
sealed class Action {
    /** Nothing. */
    object None : Action()

    /** Start ARCore's recording and the SiTAR session at this frame (frame 0). */
    data class Start(val tNs: Long, val pose: Pose) : Action()

    /** One recorded frame: `SitarSession.frame`, depth at midpoints. */
    data class Frame(val tNs: Long, val pose: Pose) : Action()

    /** Stop ARCore's recording and the SiTAR session at [tNs], then upload. */
    data class Stop(val tNs: Long, val pose: Pose, val reason: StopReason) : Action()
}

/**
 * The recorder's logic, free of Android (tested on the JVM). Start and Stop
 * take effect on the next tracked camera frame, so the SiTAR session and
 * ARCore's recording share that frame's clock. A pause of the Activity ends a
 * running recording at its last frame, cleanly and on purpose: ARCore stops
 * delivering frames while paused, so a session that went on would have a
 * hole the playback phones never see. [message] says what happened.
 *
 * Thread-safe: buttons come on the UI thread, frames on the GL thread.
 */
class RecorderFlow {
    /** Where the recorder is. */
    enum class State { IDLE, STARTING, RECORDING, STOPPING }

    /** The current state. */
    @get:Synchronized
    var state = State.IDLE
        private set

    /** What the status line says. */
    @get:Synchronized
    var message = "Press Start to record"
        private set

    private var lastT = 0L
    private var lastPose: Pose? = null

    /** The Start button: records from the next tracked frame. False while a recording runs. */
    @Synchronized
    fun pressStart(): Boolean {
        if (state != State.IDLE) return false
        state = State.STARTING
        message = "Starting… hold the phone still until tracking starts"
        return true
    }

    /** The Stop button: stops at the next tracked frame. False when nothing records. */
    @Synchronized
    fun pressStop(): Boolean {
        if (state != State.RECORDING) return false
        state = State.STOPPING
        return true
    }

    /** A camera frame; [tracking] is whether ARCore tracks (untracked frames are not recorded). */
    @Synchronized
    fun onFrame(tNs: Long, pose: Pose, tracking: Boolean): Action {
        if (!tracking || tNs <= lastT && state != State.STARTING) return Action.None
        return when (state) {
            State.IDLE -> Action.None
            State.STARTING -> {
                state = State.RECORDING
                remember(tNs, pose)
                message = "Recording… walk, then press Stop"
                Action.Start(tNs, pose)
            }
            State.RECORDING -> {
                remember(tNs, pose)
                Action.Frame(tNs, pose)
            }
            State.STOPPING -> {
                state = State.IDLE
                message = "Stopped; uploading"
                Action.Stop(tNs, pose, StopReason.BUTTON)
            }
        }
    }

    /**
     * The Activity pauses: a running recording ends at its last frame
     * ([Action.Stop] with [StopReason.PAUSE]); one that had not started yet is
     * called off.
     */
    @Synchronized
    fun onPause(): Action {
        val pose = lastPose
        return when (state) {
            State.RECORDING, State.STOPPING -> {
                state = State.IDLE
                message = "The app was paused: the recording ended at its last frame and is uploading"
                if (pose == null) Action.None else Action.Stop(lastT, pose, StopReason.PAUSE)
            }
            State.STARTING -> {
                state = State.IDLE
                message = "The app was paused before the recording started: press Start again"
                Action.None
            }
            State.IDLE -> Action.None
        }
    }

    /** A line for the status text (upload progress, failures). */
    @Synchronized
    fun say(text: String) {
        message = text
    }

    private fun remember(tNs: Long, pose: Pose) {
        lastT = tNs
        lastPose = pose
    }
}
