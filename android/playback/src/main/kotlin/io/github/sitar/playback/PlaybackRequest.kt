package io.github.sitar.playback

import java.io.File

/**
 * What one launch asks for, from the intent extras of the backend's
 * `am start -S -W -n io.github.sitar.playback/.PlaybackActivity --ei trials N
 * --ei first F --es recording FILE --es output DIR` (docs/playback-contract.md).
 * Trial `k` (0-based) of the launch is written as `trajectory_{first + k}.txt`.
 */
data class PlaybackRequest(val trials: Int, val first: Int, val recording: File, val output: File) {
    /** The file name of trial [k] of this launch. */
    fun trajectoryName(k: Int): String = "trajectory_${first + k}.txt"

    companion object {
        /** Int extra: how many trials to play. */
        const val EXTRA_TRIALS = "trials"
        /** Int extra: the number of the first trial's file. */
        const val EXTRA_FIRST = "first"
        /** String extra: the recording (mp4) to replay. */
        const val EXTRA_RECORDING = "recording"
        /** String extra: the folder for the trajectories and the status file. */
        const val EXTRA_OUTPUT = "output"
        /** The recording's name in the app's external files folder (the backend's push target). */
        const val RECORDING_FILE = "recording.mp4"
        /** The output folder's name in the app's external files folder. */
        const val OUTPUT_DIR = "out"
        /** The one-line status file in the output folder. */
        const val STATUS_FILE = "status.txt"
        /** Trials of a launch without extras (the paper's five). */
        const val DEFAULT_TRIALS = 5
        /** More trials than this in one launch is a mistake, not a plan (1000 × 15 s = 4 h). */
        const val MAX_TRIALS = 1000

        /**
         * The request of a launch. Missing extras take the defaults of a launch by
         * hand: [DEFAULT_TRIALS] trials from 0, `FILES/recording.mp4` into `FILES/out`
         * ([filesDir] is the app's external files folder). A value that cannot be
         * right throws [IllegalArgumentException] naming the extra.
         */
        fun from(extras: Extras, filesDir: File): PlaybackRequest {
            val trials = extras.int(EXTRA_TRIALS, DEFAULT_TRIALS)
            require(trials in 1..MAX_TRIALS) { "extra $EXTRA_TRIALS = $trials: expected 1 … $MAX_TRIALS" }
            val first = extras.int(EXTRA_FIRST, 0)
            require(first >= 0) { "extra $EXTRA_FIRST = $first: expected 0 or more" }
            val recording = extras.string(EXTRA_RECORDING) ?: File(filesDir, RECORDING_FILE).path
            require(recording.isNotBlank()) { "extra $EXTRA_RECORDING is empty" }
            val output = extras.string(EXTRA_OUTPUT) ?: File(filesDir, OUTPUT_DIR).path
            require(output.isNotBlank()) { "extra $EXTRA_OUTPUT is empty" }
            return PlaybackRequest(trials, first, File(recording), File(output))
        }
    }
}

/** A launch intent's extras, as far as [PlaybackRequest] reads them (Android's `Intent` in the app). */
interface Extras {
    /** The int extra [name], or [default] when it is absent. */
    fun int(name: String, default: Int): Int

    /** The string extra [name], or null when it is absent. */
    fun string(name: String): String?
}
