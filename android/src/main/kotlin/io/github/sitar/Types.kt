package io.github.sitar

/** World-from-camera pose (metres, unit quaternion) in the session's convention. */
data class Pose(
    val px: Double, val py: Double, val pz: Double,
    val qx: Double, val qy: Double, val qz: Double, val qw: Double
) {
    companion object {
        /** The identity pose at the origin. */
        @JvmField val IDENTITY = Pose(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)

        internal fun at(v: DoubleArray, i: Int) = Pose(
            v[i + PoseLayout.PX], v[i + PoseLayout.PY], v[i + PoseLayout.PZ],
            v[i + PoseLayout.QX], v[i + PoseLayout.QY], v[i + PoseLayout.QZ], v[i + PoseLayout.QW]
        )
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
        fun of(v: DoubleArray) = Summary(
            v[SummaryLayout.FRAMES].toInt(), v[SummaryLayout.MIDPOINTS].toInt(),
            v[SummaryLayout.SUBTRAJECTORIES].toInt(), v[SummaryLayout.DEPTH_SAMPLES].toInt(),
            v[SummaryLayout.DURATION_S], v[SummaryLayout.LENGTH_M], v[SummaryLayout.MEAN_DEPTH_M]
        )
    }
}

/**
 * The class and error at a timestamp; the error is in the results' unit (metres, or degrees
 * with `pose_relation` `angle_deg`), null when no result window is near.
 */
data class ErrorAt(val errorClass: ErrorClass, val errorM: Double?) {
    internal companion object {
        fun of(v: DoubleArray): ErrorAt {
            val e = v[ErrorAtLayout.ERROR_M]
            return ErrorAt(ErrorClass.of(v[ErrorAtLayout.ERROR_CLASS].toInt()), if (e.isNaN()) null else e)
        }
    }
}

/**
 * The interval of a calibrated result window, in the results' unit (metres, or degrees with
 * `pose_relation` `angle_deg`): the true error lies in [[lowerM], [upperM]] with the
 * calibration's coverage (e.g. 80 %). A calibration belongs to one SLAM system and playback
 * device. [rawM] is the window's uncalibrated estimate, null when the results do not give it.
 */
data class ErrorBounds(val lowerM: Double, val upperM: Double, val rawM: Double?) {
    internal companion object {
        /** Null when the window has no interval. */
        fun of(v: DoubleArray): ErrorBounds? {
            if (v[BoundsAtLayout.PRESENT] == 0.0) return null
            val raw = v[BoundsAtLayout.RAW_M]
            return ErrorBounds(v[BoundsAtLayout.LOWER_M], v[BoundsAtLayout.UPPER_M], if (raw.isNaN()) null else raw)
        }
    }
}

/** Where results come from (`"source"`). */
enum class ResultSource(val code: Int) {
    /** No results, or results that do not say (legacy CSV). */
    UNKNOWN(0),
    /** The walk itself, from a calibration: on the phone at stop, or by the backend at upload. */
    WALK(1),
    /** Replays of the recording on playback devices. */
    REPLAYS(2);

    companion object {
        @JvmStatic fun of(code: Int): ResultSource = values().firstOrNull { it.code == code } ?: UNKNOWN
    }
}

/** Which error results estimate (`"target"`). */
enum class ResultTarget(val code: Int) {
    /** Not said (uncalibrated results, legacy CSV) or no results. */
    UNKNOWN(0),
    /** The error of the live run: the user's own walk. */
    LIVE(1),
    /** The error expected at each place (the mean over runs). */
    EXPECTED(2);

    companion object {
        @JvmStatic fun of(code: Int): ResultTarget = values().firstOrNull { it.code == code } ?: UNKNOWN
    }
}

/**
 * Where the loaded results come from: [source], [target], the number of [runs] (the walk and
 * its replays; null when not said) and whether the calibration's runs predict the error at
 * all ([informative]; null when not said).
 */
data class Provenance(val source: ResultSource, val target: ResultTarget, val runs: Int?, val informative: Boolean?) {
    /**
     * The calibration says its runs do not predict this system's error: show the colours with
     * "this system's error cannot be told from its runs: colours are a guess".
     */
    val isGuess: Boolean get() = informative == false

    internal companion object {
        fun of(v: DoubleArray): Provenance {
            val runs = v[ProvenanceLayout.RUNS].toInt()
            val informative = v[ProvenanceLayout.INFORMATIVE].toInt()
            return Provenance(
                ResultSource.of(v[ProvenanceLayout.SOURCE].toInt()), ResultTarget.of(v[ProvenanceLayout.TARGET].toInt()),
                if (runs == 0) null else runs, if (informative < 0) null else informative == 1
            )
        }
    }
}

/**
 * A marker: position, warning-sign rotation (local +Y along the normal), surface normal; the
 * error is in the results' unit (metres, or degrees for `angle_deg`).
 */
data class Marker(
    val position: Vec3, val rotation: Quat, val normal: Vec3,
    val errorClass: ErrorClass, val subtrajectory: Int, val errorM: Double
) {
    internal companion object {
        fun at(v: DoubleArray, i: Int) = Marker(
            Vec3(v[i + MarkerLayout.PX], v[i + MarkerLayout.PY], v[i + MarkerLayout.PZ]),
            Quat(v[i + MarkerLayout.QX], v[i + MarkerLayout.QY], v[i + MarkerLayout.QZ], v[i + MarkerLayout.QW]),
            Vec3(v[i + MarkerLayout.NX], v[i + MarkerLayout.NY], v[i + MarkerLayout.NZ]),
            ErrorClass.of(v[i + MarkerLayout.ERROR_CLASS].toInt()), v[i + MarkerLayout.SUBTRAJECTORY].toInt(),
            v[i + MarkerLayout.ERROR_M]
        )

        fun list(v: DoubleArray) = (0 until v.size / MarkerLayout.SIZE).map { at(v, it * MarkerLayout.SIZE) }
    }
}

/**
 * The result of one sub-trajectory: error (in the results' unit; null when no result window is
 * near) and class.
 */
data class SubtrajectoryResult(val subtrajectory: Int, val errorM: Double?, val errorClass: ErrorClass) {
    internal companion object {
        fun at(v: DoubleArray, i: Int): SubtrajectoryResult {
            val e = v[i + SubtrajectoryResultLayout.ERROR_M]
            return SubtrajectoryResult(
                v[i + SubtrajectoryResultLayout.SUBTRAJECTORY].toInt(), if (e.isNaN()) null else e,
                ErrorClass.of(v[i + SubtrajectoryResultLayout.ERROR_CLASS].toInt())
            )
        }

        fun list(v: DoubleArray) =
            (0 until v.size / SubtrajectoryResultLayout.SIZE).map { at(v, it * SubtrajectoryResultLayout.SIZE) }
    }
}

/** A likely cause of a sub-trajectory's error (`Causes` in sitar-core; bit in `SitarEvidence.causes`). */
enum class Cause(val bit: Int, val key: String) {
    LOW_TEXTURE(1, "low_texture"), DARK(2, "dark"), OVEREXPOSED(4, "overexposed"), BLUR(8, "blur"),
    FAST_MOTION(16, "fast_motion"), FAR_SURFACE(32, "far_surface"), NO_DEPTH(64, "no_depth");

    companion object {
        /** The causes set in [bits]. */
        fun of(bits: Int): Set<Cause> = values().filter { (bits and it.bit) != 0 }.toSet()
    }
}

/** What the camera saw at a sub-trajectory's midpoint, how it moved, its depth, likely causes. */
data class Evidence(
    val subtrajectory: Int,
    val hasImage: Boolean,
    val meanBrightness: Double,
    val contrastStd: Double,
    val laplacianVar: Double,
    val cornersPer10k: Double,
    val saturatedShare: Double,
    val linearSpeedMS: Double,
    val angularSpeedDegS: Double,
    val depthGiven: Boolean,
    val depthValid: Boolean,
    val distanceM: Double,
    val depthValidShare: Double,
    val causes: Set<Cause>,
    val thumbnailWidth: Int,
    val thumbnailHeight: Int
) {
    internal companion object {
        fun of(v: DoubleArray) = Evidence(
            v[EvidenceLayout.SUBTRAJECTORY].toInt(), v[EvidenceLayout.HAS_IMAGE] != 0.0,
            v[EvidenceLayout.MEAN_BRIGHTNESS], v[EvidenceLayout.CONTRAST_STD],
            v[EvidenceLayout.LAPLACIAN_VAR], v[EvidenceLayout.CORNERS_PER_10K],
            v[EvidenceLayout.SATURATED_SHARE], v[EvidenceLayout.LINEAR_SPEED_M_S],
            v[EvidenceLayout.ANGULAR_SPEED_DEG_S], v[EvidenceLayout.DEPTH_GIVEN] != 0.0,
            v[EvidenceLayout.DEPTH_VALID] != 0.0, v[EvidenceLayout.DISTANCE_M],
            v[EvidenceLayout.DEPTH_VALID_SHARE], Cause.of(v[EvidenceLayout.CAUSES].toInt()),
            v[EvidenceLayout.THUMBNAIL_WIDTH].toInt(), v[EvidenceLayout.THUMBNAIL_HEIGHT].toInt()
        )
    }
}

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
        /** Decodes `Native.sessionRenderPlan`: `RenderPlanLayout` counts, the items, the present ends. */
        fun of(v: DoubleArray): RenderPlan {
            var i = RenderPlanLayout.SIZE
            val segments = ArrayList<Segment>()
            for (n in 0 until v[RenderPlanLayout.SEGMENTS].toInt()) {
                segments.add(
                    Segment(
                        Vec3(v[i + SegmentLayout.CX], v[i + SegmentLayout.CY], v[i + SegmentLayout.CZ]),
                        Quat(v[i + SegmentLayout.QX], v[i + SegmentLayout.QY], v[i + SegmentLayout.QZ], v[i + SegmentLayout.QW]),
                        v[i + SegmentLayout.LENGTH], v[i + SegmentLayout.SUBTRAJECTORY].toInt(),
                        ErrorClass.of(v[i + SegmentLayout.ERROR_CLASS].toInt())
                    )
                )
                i += SegmentLayout.SIZE
            }
            val joints = ArrayList<Joint>()
            for (n in 0 until v[RenderPlanLayout.JOINTS].toInt()) {
                joints.add(
                    Joint(
                        Vec3(v[i + JointLayout.PX], v[i + JointLayout.PY], v[i + JointLayout.PZ]),
                        v[i + JointLayout.SUBTRAJECTORY].toInt(), ErrorClass.of(v[i + JointLayout.ERROR_CLASS].toInt())
                    )
                )
                i += JointLayout.SIZE
            }
            val frustums = ArrayList<Frustum>()
            for (n in 0 until v[RenderPlanLayout.FRUSTUMS].toInt()) {
                frustums.add(
                    Frustum(
                        Pose.at(v, i + FrustumLayout.POSE), v[i + FrustumLayout.SUBTRAJECTORY].toInt(),
                        ErrorClass.of(v[i + FrustumLayout.ERROR_CLASS].toInt())
                    )
                )
                i += FrustumLayout.SIZE
            }
            var start: Pose? = null
            var stop: Pose? = null
            if (v[RenderPlanLayout.HAS_START] != 0.0) {
                start = Pose.at(v, i)
                i += PoseLayout.SIZE
            }
            if (v[RenderPlanLayout.HAS_STOP] != 0.0) {
                stop = Pose.at(v, i)
            }
            return RenderPlan(segments, joints, frustums, start, stop)
        }
    }
}

/** Whether the job will not change any more (`UploadState` is generated in `SitarStatus.kt`). */
val UploadState.finished: Boolean get() = code >= UploadState.DONE.code

/** A snapshot of an upload job. */
data class UploadProgress(
    val state: UploadState, val errorCode: Int, val progress: Double, val etaS: Double?,
    val bytesSent: Long, val bytesTotal: Long, val trialsDone: Int, val trialsTotal: Int,
    /** Incremented whenever (progressive or final) results were loaded into the session. */
    val resultsRevision: Int,
    val resultsTrials: Int
) {
    internal companion object {
        fun of(v: DoubleArray): UploadProgress {
            val eta = v[UploadProgressLayout.ETA_S]
            return UploadProgress(
                UploadState.of(v[UploadProgressLayout.STATE].toInt()) ?: UploadState.FAILED,
                v[UploadProgressLayout.ERROR_CODE].toInt(), v[UploadProgressLayout.PROGRESS], if (eta < 0) null else eta,
                v[UploadProgressLayout.BYTES_SENT].toLong(), v[UploadProgressLayout.BYTES_TOTAL].toLong(),
                v[UploadProgressLayout.TRIALS_DONE].toInt(), v[UploadProgressLayout.TRIALS_TOTAL].toInt(),
                v[UploadProgressLayout.RESULTS_REVISION].toInt(), v[UploadProgressLayout.RESULTS_TRIALS].toInt()
            )
        }
    }
}

/** How well the platform tracked the venue's anchor image in one observation. */
enum class Tracking(val code: Int) {
    /** Not tracked (ARCore `TrackingState.STOPPED`). */
    NONE(0),
    /** Last known pose only (`TrackingMethod.LAST_KNOWN_POSE`, or `PAUSED`): recorded, not used to align. */
    LIMITED(1),
    /** Fully tracked (`TrackingMethod.FULL_TRACKING`): the observations that align. */
    FULL(2);
}

/** A venue map cell's kind: where cameras were, or what they looked at. */
enum class CellKind(val code: Int) {
    PATH(0), SURFACE(1);

    companion object {
        @JvmStatic fun of(code: Int): CellKind = if (code == 1) SURFACE else PATH
    }
}

/** A venue map cell in this session's world frame; the error in metres. */
data class VenueCell(
    val position: Vec3, val kind: CellKind, val errorClass: ErrorClass, val sessions: Int, val errorM: Double
) {
    internal companion object {
        fun at(v: DoubleArray, i: Int) = VenueCell(
            Vec3(v[i + VenueCellLayout.PX], v[i + VenueCellLayout.PY], v[i + VenueCellLayout.PZ]),
            CellKind.of(v[i + VenueCellLayout.KIND].toInt()),
            ErrorClass.of(v[i + VenueCellLayout.ERROR_CLASS].toInt()),
            v[i + VenueCellLayout.SESSIONS].toInt(), v[i + VenueCellLayout.ERROR_M]
        )

        fun list(v: DoubleArray) = (0 until v.size / VenueCellLayout.SIZE).map { at(v, it * VenueCellLayout.SIZE) }
    }
}

/**
 * Where a target is shown: its projection when [onScreen], else the point on the ellipse
 * inside the screen's edge in its direction. Pixels from the top-left, y down; [angleRad] 0
 * points right, positive clockwise on screen.
 */
data class Guide(val onScreen: Boolean, val xPx: Double, val yPx: Double, val angleRad: Double, val distanceM: Double) {
    internal companion object {
        fun at(v: DoubleArray, i: Int) = Guide(
            v[i + GuideLayout.ON_SCREEN] != 0.0, v[i + GuideLayout.X_PX], v[i + GuideLayout.Y_PX],
            v[i + GuideLayout.ANGLE_RAD], v[i + GuideLayout.DISTANCE_M]
        )

        fun list(v: DoubleArray) = (0 until v.size / GuideLayout.SIZE).map { at(v, it * GuideLayout.SIZE) }
    }
}
