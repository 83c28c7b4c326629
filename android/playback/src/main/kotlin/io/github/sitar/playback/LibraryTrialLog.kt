package io.github.sitar.playback

import io.github.sitar.PlaybackLogger
import io.github.sitar.Pose

/**
 * A trial's log in libsitar (`sitar_playback_*` through the Kotlin library's
 * [PlaybackLogger]): poses in ARCore's convention, written as TUM with integer
 * nanoseconds, whole (the library writes `.part` and renames).
 */
class LibraryTrialLog : TrialLog {
    private val logger = PlaybackLogger("""{"convention":"arcore"}""")

    override fun log(tNs: Long, pose: Pose) = logger.log(tNs, pose)

    override val size: Long get() = logger.size

    override fun write(dir: String, index: Int) {
        logger.write(dir, index)
    }

    override fun close() = logger.close()
}
