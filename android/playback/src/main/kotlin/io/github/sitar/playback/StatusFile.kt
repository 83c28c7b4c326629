package io.github.sitar.playback

import java.io.File
import java.io.IOException

/**
 * The one-line status the backend reads from the output folder (`status.txt`):
 * `starting`, `playing K/N`, `paused K/N`, `done N/N` or `failed MESSAGE`
 * (docs/playback-contract.md). Only `failed` makes the backend act: it fails
 * this phone's share of the trials with MESSAGE. Every write is whole.
 */
class StatusFile(val file: File) {
    /** The last line written. */
    var line: String = ""
        private set

    fun starting() = write("starting")

    fun playing(trial: Int, of: Int) = write("playing ${trial + 1}/$of")

    fun paused(trial: Int, of: Int) = write("paused ${trial + 1}/$of")

    fun done(of: Int) = write("done $of/$of")

    /** Reports a failure; the message is kept on one line. */
    fun failed(message: String) = write("failed " + message.replace('\n', ' ').replace('\r', ' ').trim())

    private fun write(text: String) {
        line = text
        writeAtomically(file, text + "\n")
    }
}

/**
 * Writes [text] to [file] whole or not at all: into `.NAME.part` beside it, then a
 * rename over [file] (atomic on Android's file systems), so adb never pulls half a file.
 */
fun writeAtomically(file: File, text: String) {
    val dir = file.absoluteFile.parentFile ?: throw IOException("$file has no folder")
    if (!dir.isDirectory && !dir.mkdirs()) throw IOException("cannot create the folder $dir")
    val partial = File(dir, "." + file.name + ".part")
    partial.writeText(text)
    if (!partial.renameTo(file)) {
        partial.delete()
        throw IOException("cannot rename $partial to $file")
    }
}
