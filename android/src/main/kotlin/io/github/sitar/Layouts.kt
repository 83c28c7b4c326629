// Generated from rust/ffi/src/flat.rs by rust/ffi/tests/generated_bindings.rs; do not edit.
// Regenerate: SITAR_REGENERATE=1 cargo test -p sitar-ffi --test generated_bindings
package io.github.sitar

/** Offsets into the flat `DoubleArray` of a `SitarPose` (`rust/ffi/src/flat.rs`). */
internal object PoseLayout {
    const val PX = 0
    const val PY = 1
    const val PZ = 2
    const val QX = 3
    const val QY = 4
    const val QZ = 5
    const val QW = 6
    /** Doubles per item. */
    const val SIZE = 7
}

/** Offsets into the flat `DoubleArray` of a `SitarSummary` (`rust/ffi/src/flat.rs`). */
internal object SummaryLayout {
    const val FRAMES = 0
    const val MIDPOINTS = 1
    const val SUBTRAJECTORIES = 2
    const val DEPTH_SAMPLES = 3
    const val DURATION_S = 4
    const val LENGTH_M = 5
    const val MEAN_DEPTH_M = 6
    /** Doubles per item. */
    const val SIZE = 7
}

/** Offsets into the flat `DoubleArray` of a `SitarErrorAt` (`rust/ffi/src/flat.rs`). */
internal object ErrorAtLayout {
    const val ERROR_CLASS = 0
    const val ERROR_M = 1
    /** Doubles per item. */
    const val SIZE = 2
}

/** Offsets into the flat `DoubleArray` of a `SitarBoundsAt` (`rust/ffi/src/flat.rs`). */
internal object BoundsAtLayout {
    const val PRESENT = 0
    const val LOWER_M = 1
    const val UPPER_M = 2
    const val RAW_M = 3
    /** Doubles per item. */
    const val SIZE = 4
}

/** Offsets into the flat `DoubleArray` of a `SitarProvenance` (`rust/ffi/src/flat.rs`). */
internal object ProvenanceLayout {
    const val SOURCE = 0
    const val TARGET = 1
    const val RUNS = 2
    const val INFORMATIVE = 3
    /** Doubles per item. */
    const val SIZE = 4
}

/** Offsets into the flat `DoubleArray` of a `SitarMarker` (`rust/ffi/src/flat.rs`). */
internal object MarkerLayout {
    const val PX = 0
    const val PY = 1
    const val PZ = 2
    const val QX = 3
    const val QY = 4
    const val QZ = 5
    const val QW = 6
    const val NX = 7
    const val NY = 8
    const val NZ = 9
    const val ERROR_CLASS = 10
    const val SUBTRAJECTORY = 11
    const val ERROR_M = 12
    /** Doubles per item. */
    const val SIZE = 13
}

/** Offsets into the flat `DoubleArray` of a `SitarSubtrajectoryResult` (`rust/ffi/src/flat.rs`). */
internal object SubtrajectoryResultLayout {
    const val ERROR_M = 0
    const val SUBTRAJECTORY = 1
    const val ERROR_CLASS = 2
    /** Doubles per item. */
    const val SIZE = 3
}

/** Offsets into the flat `DoubleArray` of a `SitarEvidence` (`rust/ffi/src/flat.rs`). */
internal object EvidenceLayout {
    const val SUBTRAJECTORY = 0
    const val HAS_IMAGE = 1
    const val MEAN_BRIGHTNESS = 2
    const val CONTRAST_STD = 3
    const val LAPLACIAN_VAR = 4
    const val CORNERS_PER_10K = 5
    const val SATURATED_SHARE = 6
    const val LINEAR_SPEED_M_S = 7
    const val ANGULAR_SPEED_DEG_S = 8
    const val DEPTH_GIVEN = 9
    const val DEPTH_VALID = 10
    const val DISTANCE_M = 11
    const val DEPTH_VALID_SHARE = 12
    const val CAUSES = 13
    const val THUMBNAIL_WIDTH = 14
    const val THUMBNAIL_HEIGHT = 15
    /** Doubles per item. */
    const val SIZE = 16
}

/** Offsets into the flat `DoubleArray` of a `SitarSegment` (`rust/ffi/src/flat.rs`). */
internal object SegmentLayout {
    const val CX = 0
    const val CY = 1
    const val CZ = 2
    const val QX = 3
    const val QY = 4
    const val QZ = 5
    const val QW = 6
    const val LENGTH = 7
    const val SUBTRAJECTORY = 8
    const val ERROR_CLASS = 9
    /** Doubles per item. */
    const val SIZE = 10
}

/** Offsets into the flat `DoubleArray` of a `SitarJoint` (`rust/ffi/src/flat.rs`). */
internal object JointLayout {
    const val PX = 0
    const val PY = 1
    const val PZ = 2
    const val SUBTRAJECTORY = 3
    const val ERROR_CLASS = 4
    /** Doubles per item. */
    const val SIZE = 5
}

/** Offsets into the flat `DoubleArray` of a `SitarFrustum` (`rust/ffi/src/flat.rs`). */
internal object FrustumLayout {
    const val POSE = 0
    const val SUBTRAJECTORY = 7
    const val ERROR_CLASS = 8
    /** Doubles per item. */
    const val SIZE = 9
}

/** Offsets into the flat `DoubleArray` of a `SitarGuide` (`rust/ffi/src/flat.rs`). */
internal object GuideLayout {
    const val ON_SCREEN = 0
    const val X_PX = 1
    const val Y_PX = 2
    const val ANGLE_RAD = 3
    const val DISTANCE_M = 4
    /** Doubles per item. */
    const val SIZE = 5
}

/** Offsets into the flat `DoubleArray` of a `SitarVenueCell` (`rust/ffi/src/flat.rs`). */
internal object VenueCellLayout {
    const val PX = 0
    const val PY = 1
    const val PZ = 2
    const val KIND = 3
    const val ERROR_CLASS = 4
    const val SESSIONS = 5
    const val ERROR_M = 6
    /** Doubles per item. */
    const val SIZE = 7
}

/** Offsets into the flat `DoubleArray` of a `RenderPlanHeader` (`rust/ffi/src/flat.rs`). */
internal object RenderPlanLayout {
    const val SEGMENTS = 0
    const val JOINTS = 1
    const val FRUSTUMS = 2
    const val HAS_START = 3
    const val HAS_STOP = 4
    /** Doubles per item. */
    const val SIZE = 5
}

/** Offsets into the flat `DoubleArray` of a `SitarJobProgress` (`rust/ffi/src/flat.rs`). */
internal object UploadProgressLayout {
    const val STATE = 0
    const val ERROR_CODE = 1
    const val PROGRESS = 2
    const val ETA_S = 3
    const val BYTES_SENT = 4
    const val BYTES_TOTAL = 5
    const val TRIALS_DONE = 6
    const val TRIALS_TOTAL = 7
    const val RESULTS_REVISION = 8
    const val RESULTS_TRIALS = 9
    /** Doubles per item. */
    const val SIZE = 10
}
