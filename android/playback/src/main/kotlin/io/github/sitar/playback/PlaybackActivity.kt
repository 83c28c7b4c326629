package io.github.sitar.playback

import android.Manifest
import android.app.Activity
import android.content.Intent
import android.content.pm.PackageManager
import android.net.Uri
import android.opengl.GLES11Ext
import android.opengl.GLES20
import android.opengl.GLSurfaceView
import android.os.Bundle
import android.util.Log
import android.view.ViewGroup
import android.view.WindowManager
import android.widget.FrameLayout
import android.widget.TextView
import com.google.ar.core.PlaybackStatus
import com.google.ar.core.Session
import com.google.ar.core.exceptions.CameraNotAvailableException
import com.google.ar.core.exceptions.PlaybackFailedException
import com.google.ar.core.exceptions.UnavailableException
import io.github.sitar.Pose
import io.github.sitar.SitarException
import java.io.File
import javax.microedition.khronos.egl.EGLConfig
import javax.microedition.khronos.opengles.GL10

/**
 * The playback phone's app: `sitar serve --playback adb` starts it with
 * `am start -S -W -n io.github.sitar.playback/.PlaybackActivity --ei trials N
 * --ei first F --es recording FILE --es output DIR` (docs/playback-contract.md).
 * It replays FILE through ARCore's Playback API N times, logs the pose of every
 * camera frame through libsitar's playback logger and writes
 * `DIR/trajectory_{F+k}.txt` after trial k; `DIR/status.txt` tells the backend how
 * it goes, failures included. The logic is [PlaybackRun]; this class connects it
 * to Android and ARCore. The screen stays on; a second launch while it runs
 * (`onNewIntent`) replaces the running one.
 */
class PlaybackActivity : Activity(), GLSurfaceView.Renderer {
    private lateinit var surface: GLSurfaceView
    private lateinit var text: TextView
    private var session: Session? = null
    private var textureId = -1
    private var viewWidth = 0
    private var viewHeight = 0
    private val run = PlaybackRun { LibraryTrialLog() }

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        // A playback phone lies on a desk for hours: a dimmed screen must not pause ARCore.
        window.addFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON)
        surface = GLSurfaceView(this)
        surface.setPreserveEGLContextOnPause(true)
        surface.setEGLContextClientVersion(2)
        surface.setEGLConfigChooser(8, 8, 8, 8, 16, 0)
        surface.setRenderer(this)
        surface.setRenderMode(GLSurfaceView.RENDERMODE_CONTINUOUSLY)
        text = TextView(this)
        text.setTextColor(-0x1)
        val root = FrameLayout(this)
        val fill = ViewGroup.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.MATCH_PARENT)
        root.addView(surface, fill)
        root.addView(text, ViewGroup.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.WRAP_CONTENT))
        setContentView(root)
        launch(intent)
    }

    override fun onNewIntent(intent: Intent) {
        super.onNewIntent(intent)
        setIntent(intent)
        launch(intent)
    }

    private fun filesDir(): File = getExternalFilesDir(null) ?: File("/sdcard/Android/data/io.github.sitar.playback/files")

    private fun launch(intent: Intent) {
        val extras = IntentExtras(intent)
        val step = try {
            run.launch(PlaybackRequest.from(extras, filesDir()))
        } catch (e: IllegalArgumentException) {
            val output = extras.string(PlaybackRequest.EXTRA_OUTPUT) ?: File(filesDir(), PlaybackRequest.OUTPUT_DIR).path
            run.refuse(File(output), e.message ?: "bad extras")
        }
        perform(step)
    }

    override fun onResume() {
        super.onResume()
        if (checkSelfPermission(Manifest.permission.CAMERA) != PackageManager.PERMISSION_GRANTED) {
            // ARCore needs the camera permission even to play a recording back.
            perform(run.fail("no camera permission: grant it once (adb shell pm grant io.github.sitar.playback android.permission.CAMERA)"))
            requestPermissions(arrayOf(Manifest.permission.CAMERA), CAMERA_REQUEST)
            return
        }
        if (session == null) {
            session = try {
                Session(this)
            } catch (e: UnavailableException) {
                perform(run.fail("ARCore is not available on this phone: $e"))
                return
            }
        }
        surface.onResume()
        perform(run.onResume())
    }

    override fun onRequestPermissionsResult(requestCode: Int, permissions: Array<String>, grantResults: IntArray) {
        if (requestCode == CAMERA_REQUEST) say("camera permission ${if (grantResults.firstOrNull() == PackageManager.PERMISSION_GRANTED) "granted: launch again" else "refused"}")
    }

    override fun onPause() {
        super.onPause()
        run.onPause()
        surface.onPause()
        session?.pause()
        say(run.line)
    }

    override fun onDestroy() {
        super.onDestroy()
        run.close()
        session?.close()
        session = null
    }

    /** Carries out a [Step] on the UI thread (the GL thread must be paused to switch datasets). */
    private fun perform(step: Step) {
        when (step) {
            is Step.Play -> runOnUiThread { play(step) }
            is Step.Done -> say("done: ${step.trials} trials written")
            is Step.Failed -> {
                Log.w(TAG, step.message)
                say("failed: ${step.message}")
            }
            Step.Wait -> say(run.line)
        }
    }

    private fun play(step: Step.Play) {
        // A pause or a new launch since the step was handed out makes it stale.
        if (!run.isCurrent(step.token)) return
        val s = session ?: return
        surface.onPause()
        try {
            s.pause()
            s.setPlaybackDatasetUri(Uri.fromFile(step.recording))
            s.resume()
            run.started(step.token)
            say("trial ${step.trial + 1}/${step.of}")
        } catch (e: PlaybackFailedException) {
            perform(run.fail("ARCore cannot play ${step.recording}: $e"))
        } catch (e: CameraNotAvailableException) {
            perform(run.fail("ARCore cannot resume: $e"))
        } finally {
            surface.onResume()
        }
    }

    private fun say(line: String) = runOnUiThread { text.setText(line) }

    override fun onSurfaceCreated(gl: GL10, config: EGLConfig) {
        // ARCore needs a camera texture to update frames; nothing is drawn with it.
        val ids = IntArray(1)
        GLES20.glGenTextures(1, ids, 0)
        textureId = ids[0]
        GLES20.glBindTexture(GLES11Ext.GL_TEXTURE_EXTERNAL_OES, textureId)
        GLES20.glTexParameteri(GLES11Ext.GL_TEXTURE_EXTERNAL_OES, GLES20.GL_TEXTURE_MIN_FILTER, GLES20.GL_LINEAR)
        GLES20.glTexParameteri(GLES11Ext.GL_TEXTURE_EXTERNAL_OES, GLES20.GL_TEXTURE_MAG_FILTER, GLES20.GL_LINEAR)
    }

    override fun onSurfaceChanged(gl: GL10, width: Int, height: Int) {
        GLES20.glViewport(0, 0, width, height)
        viewWidth = width
        viewHeight = height
    }

    override fun onDrawFrame(gl: GL10) {
        GLES20.glClearColor(0f, 0f, 0f, 1f)
        GLES20.glClear(GLES20.GL_COLOR_BUFFER_BIT)
        val s = session ?: return
        try {
            @Suppress("DEPRECATION")
            s.setDisplayGeometry(windowManager.defaultDisplay.rotation, viewWidth, viewHeight)
            s.setCameraTextureName(textureId)
            val frame = s.update()
            val p = frame.camera.displayOrientedPose
            val pose = Pose(p.tx().toDouble(), p.ty().toDouble(), p.tz().toDouble(), p.qx().toDouble(), p.qy().toDouble(), p.qz().toDouble(), p.qw().toDouble())
            val step = run.onFrame(frame.timestamp, pose, playbackOf(s.playbackStatus))
            if (step != Step.Wait) perform(step)
        } catch (e: CameraNotAvailableException) {
            perform(run.fail("the camera is not available: $e"))
        } catch (e: SitarException) {
            perform(run.fail("libsitar: ${e.message}"))
        }
    }

    private fun playbackOf(status: PlaybackStatus): Playback = when (status) {
        PlaybackStatus.NONE -> Playback.NONE
        PlaybackStatus.OK -> Playback.OK
        PlaybackStatus.IO_ERROR -> Playback.IO_ERROR
        PlaybackStatus.FINISHED -> Playback.FINISHED
    }

    /** The launch intent's extras. */
    private class IntentExtras(private val intent: Intent) : Extras {
        override fun int(name: String, default: Int): Int = intent.getIntExtra(name, default)
        override fun string(name: String): String? = intent.getStringExtra(name)
    }

    private companion object {
        const val TAG = "SitarPlayback"
        const val CAMERA_REQUEST = 1
    }
}
