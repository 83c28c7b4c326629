package io.github.sitar

/** World-from-camera pose (metres, unit quaternion) in the session's convention. */
data class Pose(
    val px: Double, val py: Double, val pz: Double,
    val qx: Double, val qy: Double, val qz: Double, val qw: Double
) {
    companion object {
        /** The identity pose at the origin. */
        @JvmField val IDENTITY = Pose(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)

        internal fun at(v: DoubleArray, i: Int) = Pose(v[i], v[i + 1], v[i + 2], v[i + 3], v[i + 4], v[i + 5], v[i + 6])
    }
}

/** Pinhole intrinsics of the depth image, in its pixels. */
data class Intrinsics(val fx: Double, val fy: Double, val cx: Double, val cy: Double)

/** Error class of a sub-trajectory or marker. */
enum class ErrorClass(val code: Int) {
    UNKNOWN(0), LOW(1), MEDIUM(2), HIGH(3);

    companion object {
        @JvmStatic fun of(code: Int): ErrorClass = values().firstOrNull { it.code == code } ?: UNKNOWN
    }
}

/** What `stop` reports; counting as in ARCHITECTURE.md. */
data class Summary(
    val frames: Int, val midpoints: Int, val subtrajectories: Int, val depthSamples: Int,
    val durationS: Double, val lengthM: Double, val meanDepthM: Double
) {
    internal companion object {
        fun of(v: DoubleArray) = Summary(v[0].toInt(), v[1].toInt(), v[2].toInt(), v[3].toInt(), v[4], v[5], v[6])
    }
}

/** The class and error (metres; null when no result window is near) at a timestamp. */
data class ErrorAt(val errorClass: ErrorClass, val errorM: Double?)

/** A marker: position, warning-sign rotation (local +Y along the normal), surface normal. */
data class Marker(
    val position: Vec3, val rotation: Quat, val normal: Vec3,
    val errorClass: ErrorClass, val subtrajectory: Int, val errorM: Double
) {
    internal companion object {
        const val STRIDE = 13
        fun at(v: DoubleArray, i: Int) = Marker(
            Vec3(v[i], v[i + 1], v[i + 2]), Quat(v[i + 3], v[i + 4], v[i + 5], v[i + 6]),
            Vec3(v[i + 7], v[i + 8], v[i + 9]), ErrorClass.of(v[i + 10].toInt()), v[i + 11].toInt(), v[i + 12]
        )
    }
}

/** The result of one sub-trajectory: error (metres; null when no result window is near) and class. */
data class SubtrajectoryResult(val subtrajectory: Int, val errorM: Double?, val errorClass: ErrorClass)

/** A 3-vector (metres). */
data class Vec3(val x: Double, val y: Double, val z: Double)

/** A unit quaternion. */
data class Quat(val x: Double, val y: Double, val z: Double, val w: Double)

/** A path segment: a cylinder of [length] centred at [centre], local +Y along the path. */
data class Segment(val centre: Vec3, val rotation: Quat, val length: Double, val subtrajectory: Int, val errorClass: ErrorClass)

/** A sphere between segments. */
data class Joint(val position: Vec3, val subtrajectory: Int, val errorClass: ErrorClass)

/** A camera frustum to draw. */
data class Frustum(val pose: Pose, val subtrajectory: Int, val errorClass: ErrorClass)

/** Everything to draw the trajectory; no geometry is computed on the Kotlin side. */
data class RenderPlan(
    val segments: List<Segment>, val joints: List<Joint>, val frustums: List<Frustum>,
    val start: Pose?, val stop: Pose?
) {
    internal companion object {
        /** Decodes the layout of `flatten_render_plan` in `jni_api.rs`. */
        fun of(v: DoubleArray): RenderPlan {
            val ns = v[0].toInt()
            val nj = v[1].toInt()
            val nf = v[2].toInt()
            var i = 5
            val segments = ArrayList<Segment>(ns)
            for (n in 0 until ns) {
                segments.add(Segment(Vec3(v[i], v[i + 1], v[i + 2]), Quat(v[i + 3], v[i + 4], v[i + 5], v[i + 6]), v[i + 7], v[i + 8].toInt(), ErrorClass.of(v[i + 9].toInt())))
                i += 10
            }
            val joints = ArrayList<Joint>(nj)
            for (n in 0 until nj) {
                joints.add(Joint(Vec3(v[i], v[i + 1], v[i + 2]), v[i + 3].toInt(), ErrorClass.of(v[i + 4].toInt())))
                i += 5
            }
            val frustums = ArrayList<Frustum>(nf)
            for (n in 0 until nf) {
                frustums.add(Frustum(Pose.at(v, i), v[i + 7].toInt(), ErrorClass.of(v[i + 8].toInt())))
                i += 9
            }
            var start: Pose? = null
            var stop: Pose? = null
            if (v[3] != 0.0) {
                start = Pose.at(v, i)
                i += 7
            }
            if (v[4] != 0.0) {
                stop = Pose.at(v, i)
            }
            return RenderPlan(segments, joints, frustums, start, stop)
        }
    }
}

/** States of a background upload (`SitarJobState`). */
enum class UploadState(val code: Int) {
    STARTING(0), UPLOADING(1), PLAYING(2), ESTIMATING(3), DOWNLOADING(4), DONE(5), FAILED(6), CANCELLED(7);

    /** Whether the job will not change any more. */
    val finished: Boolean get() = code >= 5

    companion object {
        @JvmStatic fun of(code: Int): UploadState = values().firstOrNull { it.code == code } ?: FAILED
    }
}

/** A snapshot of an upload job. */
data class UploadProgress(
    val state: UploadState, val errorCode: Int, val progress: Double, val etaS: Double?,
    val bytesSent: Long, val bytesTotal: Long, val trialsDone: Int, val trialsTotal: Int,
    /** Incremented whenever (progressive or final) results were loaded into the session. */
    val resultsRevision: Int,
    val resultsTrials: Int
) {
    internal companion object {
        fun of(v: DoubleArray) = UploadProgress(
            UploadState.of(v[0].toInt()), v[1].toInt(), v[2], if (v[3] < 0) null else v[3],
            v[4].toLong(), v[5].toLong(), v[6].toInt(), v[7].toInt(), v[8].toInt(), v[9].toInt()
        )
    }
}
