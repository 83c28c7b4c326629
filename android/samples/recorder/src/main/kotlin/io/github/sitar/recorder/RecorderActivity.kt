package io.github.sitar.recorder

import android.Manifest
import android.app.Activity
import android.content.Context
import android.content.pm.PackageManager
import android.hardware.camera2.CameraAccessException
import android.hardware.camera2.CameraCharacteristics
import android.hardware.camera2.CameraManager
import android.net.Uri
import android.opengl.GLES20
import android.opengl.GLSurfaceView
import android.graphics.BitmapFactory
import android.os.Bundle
import android.os.Handler
import android.os.Looper
import android.util.Log
import android.view.ViewGroup
import android.widget.Button
import android.widget.FrameLayout
import android.widget.ImageView
import android.widget.LinearLayout
import android.widget.TextView
import com.google.ar.core.AugmentedImage
import com.google.ar.core.AugmentedImageDatabase
import com.google.ar.core.Config
import com.google.ar.core.Frame
import com.google.ar.core.RecordingConfig
import com.google.ar.core.Session
import com.google.ar.core.TrackingState
import com.google.ar.core.exceptions.CameraNotAvailableException
import com.google.ar.core.exceptions.NotYetAvailableException
import com.google.ar.core.exceptions.RecordingFailedException
import com.google.ar.core.exceptions.UnavailableException
import io.github.sitar.Guide
import io.github.sitar.Marker
import io.github.sitar.Pose
import io.github.sitar.RenderPlan
import io.github.sitar.Sitar
import io.github.sitar.SitarException
import io.github.sitar.SitarSession
import io.github.sitar.UploadJob
import io.github.sitar.VenueCell
import io.github.sitar.finished
import io.github.sitar.UploadState
import io.github.sitar.finished
import java.io.File
import java.io.IOException
import javax.microedition.khronos.egl.EGLConfig
import javax.microedition.khronos.opengles.GL10

/**
 * The SiTAR recorder as a plain ARCore app: Start and Stop buttons, ARCore's
 * Recording API to an mp4, one `SitarSession.frame` per tracked camera frame,
 * the depth image at midpoints, upload with progress, then the trajectory
 * coloured by estimated error and the markers. The logic of when things start
 * and stop is [RecorderFlow]; a pause of the app ends a running recording
 * cleanly (both the mp4 and the SiTAR session stop at the last frame) and says
 * so. Set [SERVER_URL] to where `sitar serve` runs.
 *
 * In a venue: ARCore tracks the venue's printed anchor image ([VenueAnchor], an Augmented
 * Images database of the committed image) and every observation goes to the session; with the
 * venue's `map.json` at `<external files>/venue-map.json` the session is aligned to it once the
 * image is fully tracked, its cells are drawn (the "Venue map" button toggles them), arrows at
 * the screen's edge point to markers and high venue cells out of view, and each marker pulses
 * for its first seconds in view ([Kineticon]).
 */
class RecorderActivity : Activity(), GLSurfaceView.Renderer {
    private lateinit var surface: GLSurfaceView
    private lateinit var status: TextView
    private lateinit var startButton: Button
    private lateinit var stopButton: Button
    private val flow = RecorderFlow()
    private val background = CameraBackground()
    private val drawing = PlanDrawing()
    private val handler = Handler(Looper.getMainLooper())
    private var session: Session? = null
    private var sensorOrientation = 90
    private var viewWidth = 0
    private var viewHeight = 0
    @Volatile private var sitar: SitarSession? = null
    @Volatile private var upload: UploadJob? = null
    @Volatile private var plan: RenderPlan? = null
    @Volatile private var markers: List<Marker> = emptyList()
    private var drawnRevision = 0
    private lateinit var evidenceText: TextView
    private lateinit var evidenceImage: ImageView
    private val view = FloatArray(16)
    private val projection = FloatArray(16)
    private lateinit var arrowLayer: FrameLayout
    private val arrowViews = mutableListOf<TextView>()
    private val kineticon = Kineticon()
    private val startedAt = System.nanoTime()
    @Volatile private var venueCells: List<VenueCell> = emptyList()
    @Volatile private var mapShown = true
    private var venueFrames = 0

    private val mp4: File get() = File(getExternalFilesDir(null), "recording.mp4")

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        // Unpinned https uploads trust Android's trust store (the bundled roots without it).
        Sitar.init(this)
        surface = GLSurfaceView(this)
        surface.setPreserveEGLContextOnPause(true)
        surface.setEGLContextClientVersion(2)
        surface.setEGLConfigChooser(8, 8, 8, 8, 16, 0)
        surface.setRenderer(this)
        surface.setRenderMode(GLSurfaceView.RENDERMODE_CONTINUOUSLY)
        status = TextView(this)
        status.setTextColor(-0x1)
        status.setBackgroundColor(0x66000000)
        startButton = Button(this)
        startButton.setText("Start")
        startButton.setOnClickListener { if (flow.pressStart()) clearResults() }
        stopButton = Button(this)
        stopButton.setText("Stop")
        stopButton.setOnClickListener { flow.pressStop() }
        val controls = LinearLayout(this)
        controls.setOrientation(LinearLayout.VERTICAL)
        val wrap = ViewGroup.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.WRAP_CONTENT)
        controls.addView(status, wrap)
        controls.addView(startButton, wrap)
        controls.addView(stopButton, wrap)
        evidenceText = TextView(this)
        evidenceText.setTextColor(-0x1)
        evidenceImage = ImageView(this)
        controls.addView(evidenceText, wrap)
        controls.addView(evidenceImage, wrap)
        val mapButton = Button(this)
        mapButton.setText("Venue map")
        mapButton.setOnClickListener { mapShown = !mapShown }
        controls.addView(mapButton, wrap)
        val root = FrameLayout(this)
        val fill = ViewGroup.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.MATCH_PARENT)
        root.addView(surface, fill)
        arrowLayer = FrameLayout(this)
        root.addView(arrowLayer, fill)
        root.addView(controls, wrap)
        setContentView(root)
    }

    override fun onResume() {
        super.onResume()
        if (checkSelfPermission(Manifest.permission.CAMERA) != PackageManager.PERMISSION_GRANTED) {
            requestPermissions(arrayOf(Manifest.permission.CAMERA), CAMERA_REQUEST)
            return
        }
        val s = session ?: try {
            Session(this).also { created ->
                val config = created.config
                if (created.isDepthModeSupported(Config.DepthMode.AUTOMATIC)) config.setDepthMode(Config.DepthMode.AUTOMATIC)
                anchorDatabase(created)?.let { config.setAugmentedImageDatabase(it) }
                created.configure(config)
                session = created
                sensorOrientation = backCameraOrientation(created)
            }
        } catch (e: UnavailableException) {
            flow.say("ARCore is not available: $e")
            showStatus()
            return
        }
        try {
            s.resume()
        } catch (e: CameraNotAvailableException) {
            flow.say("The camera is not available: $e")
            showStatus()
            return
        }
        surface.onResume()
        handler.postDelayed(poll, POLL_MS)
    }

    override fun onRequestPermissionsResult(requestCode: Int, permissions: Array<String>, grantResults: IntArray) {
        if (requestCode == CAMERA_REQUEST && grantResults.firstOrNull() != PackageManager.PERMISSION_GRANTED) {
            flow.say("SiTAR needs the camera")
            showStatus()
        }
    }

    override fun onPause() {
        super.onPause()
        handler.removeCallbacks(poll)
        // The GL thread stops first, so the pause below is the only one touching the sessions.
        surface.onPause()
        val stop = flow.onPause()
        if (stop is Action.Stop) finishRecording(stop)
        session?.pause()
        showStatus()
    }

    override fun onDestroy() {
        super.onDestroy()
        upload?.close()
        sitar?.close()
        session?.close()
        session = null
    }

    /** The venue's anchor image as ARCore's Augmented Images database (null if the asset is missing). */
    private fun anchorDatabase(s: Session): AugmentedImageDatabase? = try {
        val bitmap = assets.open(VenueAnchor.ASSET).use { BitmapFactory.decodeStream(it) }
        AugmentedImageDatabase(s).also { it.addImage(VenueAnchor.ID, bitmap, VenueAnchor.WIDTH_M) }
    } catch (e: IOException) {
        Log.w(TAG, "no venue anchor image: $e")
        null
    }

    /** Every update of the anchor image this frame, to the session (while recording). */
    private fun reportAnchor(frame: Frame) {
        val s = sitar ?: return
        if (flow.state != RecorderFlow.State.RECORDING) return
        for (image in frame.getUpdatedTrackables(AugmentedImage::class.java)) {
            if (image.name != VenueAnchor.ID) continue
            val state = image.trackingState
            val tracking = VenueAnchor.tracking(state == TrackingState.TRACKING, state == TrackingState.PAUSED,
                image.trackingMethod == AugmentedImage.TrackingMethod.FULL_TRACKING)
            val c = image.centerPose
            s.anchor(frame.timestamp, VenueAnchor.ID,
                Pose(c.tx().toDouble(), c.ty().toDouble(), c.tz().toDouble(), c.qx().toDouble(), c.qy().toDouble(), c.qz().toDouble(), c.qw().toDouble()),
                tracking)
        }
    }

    /** The venue layer, the marker pulses and the edge arrows of this frame. */
    private fun drawVenue(s: SitarSession, frame: Frame, p: RenderPlan?) {
        // The alignment is refined as observations arrive: refresh the cells twice a second.
        if (venueFrames++ % 15 == 0) {
            venueCells = try { s.venueCells() } catch (e: SitarException) { emptyList() }
        }
        if (mapShown && venueCells.isNotEmpty()) drawing.drawVenue(venueCells, view, projection)
        // projection[5] = 1 / tan(vfov / 2) of the display-oriented projection.
        val vfovDeg = Math.toDegrees(2.0 * Math.atan(1.0 / projection[5]))
        val guides = try { s.guide(pose(frame), vfovDeg, viewWidth, viewHeight, EDGE_MARGIN_PX) } catch (e: SitarException) { emptyList<Guide>() }
        val nowS = (System.nanoTime() - startedAt) / 1e9
        if (p != null) {
            drawing.draw(p, markers, view, projection) { i -> if (i < guides.size) kineticon.scale(i, guides[i].onScreen, nowS).toFloat() else 1f }
        }
        val arrows = VenueView.edgeArrows(guides)
        runOnUiThread { showArrows(arrows) }
    }

    /** One arrow view per off-screen target, pooled. */
    private fun showArrows(arrows: List<EdgeArrow>) {
        while (arrowViews.size < arrows.size) {
            val v = TextView(this)
            v.setText("\u27A4")
            v.setTextColor(-0x1)
            arrowLayer.addView(v, ViewGroup.LayoutParams(ViewGroup.LayoutParams.WRAP_CONTENT, ViewGroup.LayoutParams.WRAP_CONTENT))
            arrowViews += v
        }
        for ((i, v) in arrowViews.withIndex()) {
            val a = arrows.getOrNull(i)
            v.setVisibility(if (a == null) android.view.View.INVISIBLE else android.view.View.VISIBLE)
            if (a == null) continue
            v.setX(a.x)
            v.setY(a.y)
            v.setRotation(a.rotationDeg)
        }
    }

    private fun backCameraOrientation(s: Session): Int = try {
        val cameras = getSystemService(Context.CAMERA_SERVICE) as CameraManager
        cameras.getCameraCharacteristics(s.cameraConfig.cameraId).get(CameraCharacteristics.SENSOR_ORIENTATION) ?: 90
    } catch (e: CameraAccessException) {
        90
    }

    private fun pose(frame: Frame): Pose {
        val p = frame.camera.displayOrientedPose
        return Pose(p.tx().toDouble(), p.ty().toDouble(), p.tz().toDouble(), p.qx().toDouble(), p.qy().toDouble(), p.qz().toDouble(), p.qw().toDouble())
    }

    override fun onSurfaceCreated(gl: GL10, config: EGLConfig) {
        background.create()
        drawing.create()
    }

    override fun onSurfaceChanged(gl: GL10, width: Int, height: Int) {
        GLES20.glViewport(0, 0, width, height)
        viewWidth = width
        viewHeight = height
    }

    override fun onDrawFrame(gl: GL10) {
        GLES20.glClear(GLES20.GL_COLOR_BUFFER_BIT or GLES20.GL_DEPTH_BUFFER_BIT)
        val s = session ?: return
        val frame = try {
            @Suppress("DEPRECATION")
            s.setDisplayGeometry(windowManager.defaultDisplay.rotation, viewWidth, viewHeight)
            s.setCameraTextureName(background.textureId)
            s.update()
        } catch (e: CameraNotAvailableException) {
            return
        }
        background.draw(frame)
        val camera = frame.camera
        val tracking = camera.trackingState == TrackingState.TRACKING
        try {
            when (val action = flow.onFrame(frame.timestamp, pose(frame), tracking)) {
                is Action.Start -> startRecording(s, action)
                is Action.Frame -> recordFrame(frame, action)
                is Action.Stop -> finishRecording(action)
                Action.None -> Unit
            }
            reportAnchor(frame)
        } catch (e: SitarException) {
            Log.w(TAG, "SiTAR: ${e.message}")
        }
        val p = plan
        val current = sitar
        if (tracking && (p != null || current != null)) {
            camera.getViewMatrix(view, 0)
            camera.getProjectionMatrix(projection, 0, 0.05f, 100f)
            if (current != null) drawVenue(current, frame, p) else if (p != null) drawing.draw(p, markers, view, projection)
        }
    }

    private fun startRecording(s: Session, start: Action.Start) {
        // Stopped explicitly on Stop and on pause, so the mp4 and the SiTAR session always end together.
        try {
            s.startRecording(RecordingConfig(s).setMp4DatasetUri(Uri.fromFile(mp4)).setAutoStopOnPause(false))
        } catch (e: RecordingFailedException) {
            flow.say("ARCore cannot record: $e")
        }
        val config = Json.obj("convention" to "arcore", "server_url" to SERVER_URL)
        val created = SitarSession(config)
        created.start(start.tNs, start.pose)
        // The venue's map (`GET /v1/venues/{id}/map.json`, e.g. pushed with adb): aligned once the anchor is seen.
        val map = File(getExternalFilesDir(null), "venue-map.json")
        if (map.isFile) {
            try {
                created.loadVenue(map.readText())
            } catch (e: SitarException) {
                flow.say("The venue map was not loaded: ${e.message}")
            }
        }
        kineticon.reset()
        venueCells = emptyList()
        sitar?.close()
        sitar = created
    }

    private fun recordFrame(frame: Frame, f: Action.Frame) {
        val s = sitar ?: return
        val p = f.pose
        // The 8-double overload allocates nothing on the per-frame path.
        val flags = s.frame(f.tNs, p.px, p.py, p.pz, p.qx, p.qy, p.qz, p.qw)
        if (flags and SitarSession.MIDPOINT != 0) {
            giveImage(s, frame)
            giveDepth(s, frame)
        }
    }

    /** The camera image's Y plane at a midpoint: its thumbnail and properties are the evidence
     * shown for a marker (the paper's backup view when the situated view is unreliable). */
    private fun giveImage(s: SitarSession, frame: Frame) {
        val image = try {
            frame.acquireCameraImage()
        } catch (e: NotYetAvailableException) {
            return
        }
        try {
            @Suppress("DEPRECATION")
            val rotation = displayRotationDeg(sensorOrientation, windowManager.defaultDisplay.rotation)
            val plane = image.planes[0]
            s.image(plane.buffer, image.width, image.height, plane.rowStride, rotation)
        } catch (e: SitarException) {
            Log.w(TAG, "camera image skipped: $e")
        } finally {
            image.close()
        }
    }

    /** Shows what the camera saw at the selected marker's sub-trajectory: thumbnail and causes. */
    private fun showEvidence(s: SitarSession, marker: Marker) {
        val evidence = s.evidence(marker.subtrajectory)
        val causes = if (evidence.causes.isEmpty()) "no likely cause seen" else evidence.causes.joinToString(" ") { it.key }
        evidenceText.setText("Marker at sub-trajectory ${marker.subtrajectory}: $causes")
        val jpeg = s.thumbnail(marker.subtrajectory)
        if (jpeg.isNotEmpty()) evidenceImage.setImageBitmap(BitmapFactory.decodeByteArray(jpeg, 0, jpeg.size))
    }

    private fun giveDepth(s: SitarSession, frame: Frame) {
        val image = try {
            frame.acquireDepthImage16Bits()
        } catch (e: NotYetAvailableException) {
            return // the midpoint keeps its place without a depth sample
        }
        try {
            val ci = frame.camera.imageIntrinsics
            val dims = ci.imageDimensions
            val k = depthIntrinsics(ci.focalLength, ci.principalPoint, dims[0], dims[1], image.width, image.height)
            @Suppress("DEPRECATION")
            val rotation = displayRotationDeg(sensorOrientation, windowManager.defaultDisplay.rotation)
            val plane = image.planes[0]
            s.depth(plane.buffer, image.width, image.height, plane.rowStride, k, rotation)
        } catch (e: SitarException) {
            // INVALID_ARGUMENT for an unusable sample (no depth at the centre): skipped.
        } finally {
            image.close()
        }
    }

    private fun finishRecording(stop: Action.Stop) {
        val s = sitar ?: return
        try {
            session?.stopRecording()
        } catch (e: RecordingFailedException) {
            Log.w(TAG, "ARCore did not stop recording cleanly: $e")
        }
        val summary = s.stop(stop.tNs, stop.pose)
        plan = s.renderPlan()
        val fields = mutableListOf<Pair<String, Any>>("trials" to TRIALS, "setting" to "trim_mean_30", "playback" to "adb")
        if (SERVER_TOKEN.isNotEmpty()) fields += "server_token" to SERVER_TOKEN
        if (SERVER_CERT_SHA256.isNotEmpty()) fields += "server_cert_sha256" to SERVER_CERT_SHA256
        val options = Json.obj(*fields.toTypedArray())
        upload?.close()
        upload = s.upload(mp4.path, options)
        val why = if (stop.reason == StopReason.PAUSE) "the app was paused, so the recording ended" else "stopped"
        flow.say("${summary.frames} frames, %.1f s, %.2f m: $why; uploading".format(summary.durationS, summary.lengthM))
    }

    private fun clearResults() {
        plan = null
        markers = emptyList()
        drawnRevision = 0
    }

    /** Every [POLL_MS] on the UI thread: upload progress, and new results when they arrive. */
    private val poll: Runnable = object : Runnable {
        override fun run() {
            val job = upload
            val s = sitar
            if (job != null && s != null) {
                val p = job.progress()
                if (p.resultsRevision != drawnRevision) {
                    drawnRevision = p.resultsRevision
                    plan = s.renderPlan()
                    markers = s.markers()
                    // The worst marker is the one selected by default.
                    markers.sortedByDescending { it.errorM }.firstOrNull()?.let { showEvidence(s, it) }
                }
                when (p.state) {
                    UploadState.FAILED -> flow.say("Upload failed: ${job.message()}")
                    UploadState.DONE -> flow.say("Results: ${markers.size} marker(s)" + if (s.resultsUnreliable()) " — too noisy to trust" else "")
                    else -> flow.say("${p.state}: ${(p.progress * 100).toInt()} % (${p.trialsDone}/${p.trialsTotal} trials)")
                }
                if (p.state.finished) {
                    job.close()
                    upload = null
                }
            }
            showStatus()
            handler.postDelayed(this, POLL_MS)
        }
    }

    private fun showStatus() {
        status.setText(flow.message)
        startButton.setEnabled(flow.state == RecorderFlow.State.IDLE && upload == null)
        stopButton.setEnabled(flow.state == RecorderFlow.State.RECORDING)
    }

    private companion object {
        const val TAG = "SitarRecorder"
        /** Where `sitar serve` listens (the phone and the backend on one network). */
        const val SERVER_URL = "http://192.168.0.10:8000"
        /** The backend's app token: `sitar token create --data DIR --role app --name NAME`. */
        const val SERVER_TOKEN = ""
        /** With an https:// URL and `sitar serve --tls`'s self-signed certificate: the SHA-256
         *  fingerprint it prints (AB:CD:…); empty: the platform's roots. */
        const val SERVER_CERT_SHA256 = ""
        const val TRIALS = 10
        const val CAMERA_REQUEST = 1
        const val POLL_MS = 500L
        /** The edge arrows' ellipse lies this far inside the screen's edges. */
        const val EDGE_MARGIN_PX = 80.0
    }
}
