package io.github.sitar.recorder

import io.github.sitar.CellKind
import io.github.sitar.ErrorClass
import io.github.sitar.Guide
import io.github.sitar.Tracking

/** The venue's anchor image as the recorder tracks it: its name in the image database and its printed width. */
object VenueAnchor {
    /** The image's name (ARCore's `AugmentedImage.getName()`): the anchor id sent to the session. */
    const val ID = "venue-anchor"
    /** The asset (the committed image, `unity-plugin/Documentation~/venue-anchor/`). */
    const val ASSET = "venue-anchor.png"
    /** The printed width on A4 (m); A3 prints it at 0.26 m. */
    const val WIDTH_M = 0.18f

    /**
     * The tracking state of an `AugmentedImage` observation: full while ARCore tracks the image
     * itself (`TrackingState.TRACKING` with `TrackingMethod.FULL_TRACKING`), limited when it only
     * keeps its last known pose (or tracking is paused), none once it stopped.
     */
    fun tracking(tracking: Boolean, paused: Boolean, fullTracking: Boolean): Tracking = when {
        tracking && fullTracking -> Tracking.FULL
        tracking || paused -> Tracking.LIMITED
        else -> Tracking.NONE
    }
}

/** An arrow at the screen's edge to an off-screen target: where, and its clockwise rotation. */
data class EdgeArrow(val index: Int, val x: Float, val y: Float, val rotationDeg: Float, val distanceM: Double)

/**
 * A kineticon: each target pulses (its size swings around 1) for its first [pulseSeconds] on
 * screen, then keeps still; the clock starts the first time it is seen.
 */
class Kineticon(private val pulseSeconds: Double = 3.0, private val pulsesPerSecond: Double = 1.5, private val amplitude: Double = 0.35) {
    private var firstSeen = DoubleArray(0)

    /** Forgets every target (new results, new markers). */
    fun reset() = firstSeen.fill(Double.NaN)

    /** The scale of target [index] at [nowS]. */
    fun scale(index: Int, onScreen: Boolean, nowS: Double): Double {
        require(index >= 0) { "index $index" }
        if (index >= firstSeen.size) {
            val old = firstSeen.size
            firstSeen = firstSeen.copyOf(maxOf(index + 1, 2 * old))
            for (i in old until firstSeen.size) firstSeen[i] = Double.NaN
        }
        if (firstSeen[index].isNaN()) {
            if (!onScreen) return 1.0
            firstSeen[index] = nowS
        }
        val age = nowS - firstSeen[index]
        if (age < 0 || age >= pulseSeconds) return 1.0
        val fade = 1.0 - age / pulseSeconds
        return 1.0 + amplitude * fade * Math.abs(Math.sin(Math.PI * pulsesPerSecond * age))
    }
}

/** Edge arrows and the venue layer's colours. */
object VenueView {
    /**
     * One arrow per off-screen target: Android's views share the guide's pixels (origin top-left,
     * y down) and rotate clockwise, so the guide's angle is the rotation as it is.
     */
    fun edgeArrows(guides: List<Guide>): List<EdgeArrow> = guides.withIndex()
        .filter { !it.value.onScreen }
        .map { EdgeArrow(it.index, it.value.xPx.toFloat(), it.value.yPx.toFloat(), Math.toDegrees(it.value.angleRad).toFloat(), it.value.distanceM) }

    /**
     * The colour (r, g, b, a) a venue cell is drawn with: the paper's class colours (blue low,
     * yellow medium, red high, grey unknown), surface cells as translucent tiles, path cells as
     * a faint trail.
     */
    fun cellColor(kind: CellKind, errorClass: ErrorClass): FloatArray {
        val rgb = when (errorClass) {
            ErrorClass.HIGH -> floatArrayOf(0.9f, 0.1f, 0.1f)
            ErrorClass.MEDIUM -> floatArrayOf(0.95f, 0.85f, 0.1f)
            ErrorClass.LOW -> floatArrayOf(0.15f, 0.35f, 0.95f)
            ErrorClass.UNKNOWN -> floatArrayOf(0.6f, 0.6f, 0.6f)
        }
        return floatArrayOf(rgb[0], rgb[1], rgb[2], if (kind == CellKind.SURFACE) 0.45f else 0.15f)
    }
}
