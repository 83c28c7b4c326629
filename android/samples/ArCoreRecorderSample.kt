// SAMPLE — not compiled by this repository (it needs the ARCore SDK and an
// Android app). It shows the calls an ARCore app makes, in order:
// recording with the Recording API, one `frame` per camera frame, depth at
// midpoints from `acquireDepthImage16Bits`, upload, then drawing.
package io.github.sitar.sample

import android.media.Image
import android.net.Uri
import android.view.Surface
import com.google.ar.core.Config
import com.google.ar.core.Frame
import com.google.ar.core.RecordingConfig
import com.google.ar.core.Session
import com.google.ar.core.TrackingState
import com.google.ar.core.exceptions.NotYetAvailableException
import io.github.sitar.Intrinsics
import io.github.sitar.SitarException
import io.github.sitar.SitarSession
import io.github.sitar.UploadJob
import io.github.sitar.UploadState

class ArCoreRecorderSample(private val arSession: Session, private val serverUrl: String) {
    private var sitar: SitarSession? = null
    private var upload: UploadJob? = null
    private lateinit var recording: Uri

    /** Start button: ARCore records camera + IMU to an mp4; SiTAR starts at frame 0. */
    fun onStart(frame: Frame, mp4: Uri) {
        arSession.configure(arSession.config.apply { depthMode = Config.DepthMode.AUTOMATIC })
        recording = mp4
        arSession.startRecording(RecordingConfig(arSession).setMp4DatasetUri(mp4).setAutoStopOnPause(true))
        val s = SitarSession("""{"convention":"arcore","server_url":"$serverUrl"}""")
        val p = frame.camera.displayOrientedPose
        s.start(frame.timestamp, p.tx().toDouble(), p.ty().toDouble(), p.tz().toDouble(), p.qx().toDouble(), p.qy().toDouble(), p.qz().toDouble(), p.qw().toDouble())
        sitar = s
    }

    /** Every camera frame (GL thread): allocation-free unless it is a midpoint. */
    fun onFrame(frame: Frame, displayRotation: Int, sensorOrientationDeg: Int) {
        val s = sitar ?: return
        if (frame.camera.trackingState != TrackingState.TRACKING) return
        val p = frame.camera.displayOrientedPose
        val flags = s.frame(frame.timestamp, p.tx().toDouble(), p.ty().toDouble(), p.tz().toDouble(), p.qx().toDouble(), p.qy().toDouble(), p.qz().toDouble(), p.qw().toDouble())
        if (flags and SitarSession.MIDPOINT != 0) {
            giveDepth(s, frame, displayRotation, sensorOrientationDeg)
        }
    }

    private fun giveDepth(s: SitarSession, frame: Frame, displayRotation: Int, sensorOrientationDeg: Int) {
        val image: Image = try {
            frame.acquireDepthImage16Bits()
        } catch (e: NotYetAvailableException) {
            return // the midpoint keeps its place without a depth sample
        }
        try {
            // Camera intrinsics are for the CPU image; scale them to the depth image.
            val ci = frame.camera.imageIntrinsics
            val sx = image.width.toDouble() / ci.imageDimensions[0]
            val sy = image.height.toDouble() / ci.imageDimensions[1]
            val k = Intrinsics(ci.focalLength[0] * sx, ci.focalLength[1] * sy, ci.principalPoint[0] * sx, ci.principalPoint[1] * sy)
            // Clockwise rotation from the sensor image to the display (back camera).
            val displayDeg = when (displayRotation) {
                Surface.ROTATION_90 -> 90; Surface.ROTATION_180 -> 180; Surface.ROTATION_270 -> 270; else -> 0
            }
            val rotation = (sensorOrientationDeg - displayDeg + 360) % 360
            val plane = image.planes[0]
            s.depth(plane.buffer, image.width, image.height, plane.rowStride, k, rotation)
        } catch (e: SitarException) {
            // INVALID_ARGUMENT from an unusable sample (no depth at the centre): skip it.
        } finally {
            image.close()
        }
    }

    /** Stop button: stop recording and upload in the background. */
    fun onStop(frame: Frame, recordingPath: String) {
        val s = sitar ?: return
        arSession.stopRecording()
        val p = frame.camera.displayOrientedPose
        val summary = s.stop(frame.timestamp, io.github.sitar.Pose(p.tx().toDouble(), p.ty().toDouble(), p.tz().toDouble(), p.qx().toDouble(), p.qy().toDouble(), p.qz().toDouble(), p.qw().toDouble()))
        android.util.Log.i("sitar", "recorded $summary")
        upload = s.upload(recordingPath, """{"trials":10,"setting":"trim_mean_30","playback":"adb"}""")
    }

    /** Poll from the UI thread, e.g. every 500 ms; redraw when results arrive. */
    fun onPoll(draw: (io.github.sitar.RenderPlan, List<io.github.sitar.Marker>, Boolean) -> Unit): String {
        val s = sitar ?: return ""
        val job = upload ?: return ""
        val p = job.progress()
        if (p.resultsRevision > 0) draw(s.renderPlan(), s.markers(), s.resultsUnreliable())
        return when (p.state) {
            UploadState.FAILED -> "Failed: ${job.message()}"
            UploadState.DONE -> "Done"
            else -> "${p.state}: ${(p.progress * 100).toInt()} % (${p.trialsDone}/${p.trialsTotal} trials)"
        }
    }

    fun onDestroy() {
        upload?.close()
        sitar?.close()
    }
}
