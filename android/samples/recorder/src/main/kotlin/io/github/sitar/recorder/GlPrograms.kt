package io.github.sitar.recorder

import android.opengl.GLES11Ext
import android.opengl.GLES20
import android.opengl.Matrix
import com.google.ar.core.Coordinates2d
import com.google.ar.core.Frame
import io.github.sitar.CellKind
import io.github.sitar.ErrorClass
import io.github.sitar.Marker
import io.github.sitar.RenderPlan
import io.github.sitar.VenueCell
import java.nio.ByteBuffer
import java.nio.ByteOrder
import java.nio.FloatBuffer

private fun floats(n: Int): FloatBuffer = ByteBuffer.allocateDirect(4 * n).order(ByteOrder.nativeOrder()).asFloatBuffer()

private fun compile(type: Int, source: String): Int {
    val shader = GLES20.glCreateShader(type)
    GLES20.glShaderSource(shader, source)
    GLES20.glCompileShader(shader)
    val ok = IntArray(1)
    GLES20.glGetShaderiv(shader, GLES20.GL_COMPILE_STATUS, ok, 0)
    check(ok[0] != 0) { "shader: ${GLES20.glGetShaderInfoLog(shader)}" }
    return shader
}

private fun program(vertex: String, fragment: String): Int {
    val p = GLES20.glCreateProgram()
    GLES20.glAttachShader(p, compile(GLES20.GL_VERTEX_SHADER, vertex))
    GLES20.glAttachShader(p, compile(GLES20.GL_FRAGMENT_SHADER, fragment))
    GLES20.glLinkProgram(p)
    val ok = IntArray(1)
    GLES20.glGetProgramiv(p, GLES20.GL_LINK_STATUS, ok, 0)
    check(ok[0] != 0) { "program: ${GLES20.glGetProgramInfoLog(p)}" }
    return p
}

/** Draws ARCore's camera image behind everything (the external OES texture ARCore fills). */
class CameraBackground {
    /** The texture to hand to `Session.setCameraTextureName`. */
    var textureId = 0
        private set
    private var program = 0
    private val quad = floats(8).apply { put(floatArrayOf(-1f, -1f, 1f, -1f, -1f, 1f, 1f, 1f)); rewind() }
    private val uv = floats(8)

    /** On the GL thread, once the surface exists. */
    fun create() {
        val ids = IntArray(1)
        GLES20.glGenTextures(1, ids, 0)
        textureId = ids[0]
        val target = GLES11Ext.GL_TEXTURE_EXTERNAL_OES
        GLES20.glBindTexture(target, textureId)
        GLES20.glTexParameteri(target, GLES20.GL_TEXTURE_WRAP_S, GLES20.GL_CLAMP_TO_EDGE)
        GLES20.glTexParameteri(target, GLES20.GL_TEXTURE_WRAP_T, GLES20.GL_CLAMP_TO_EDGE)
        GLES20.glTexParameteri(target, GLES20.GL_TEXTURE_MIN_FILTER, GLES20.GL_LINEAR)
        GLES20.glTexParameteri(target, GLES20.GL_TEXTURE_MAG_FILTER, GLES20.GL_LINEAR)
        program = program(
            "attribute vec4 a_Position; attribute vec2 a_Uv; varying vec2 v_Uv;" +
                "void main() { gl_Position = a_Position; v_Uv = a_Uv; }",
            "#extension GL_OES_EGL_image_external : require\n" +
                "precision mediump float; varying vec2 v_Uv; uniform samplerExternalOES u_Texture;" +
                "void main() { gl_FragColor = texture2D(u_Texture, v_Uv); }"
        )
    }

    /** Draws [frame]'s camera image full screen. */
    fun draw(frame: Frame) {
        if (frame.hasDisplayGeometryChanged()) {
            frame.transformCoordinates2d(Coordinates2d.OPENGL_NORMALIZED_DEVICE_COORDINATES, quad, Coordinates2d.TEXTURE_NORMALIZED, uv)
            quad.rewind()
            uv.rewind()
        }
        GLES20.glDisable(GLES20.GL_DEPTH_TEST)
        GLES20.glDepthMask(false)
        GLES20.glUseProgram(program)
        GLES20.glActiveTexture(GLES20.GL_TEXTURE0)
        GLES20.glBindTexture(GLES11Ext.GL_TEXTURE_EXTERNAL_OES, textureId)
        GLES20.glUniform1i(GLES20.glGetUniformLocation(program, "u_Texture"), 0)
        val position = GLES20.glGetAttribLocation(program, "a_Position")
        val texCoord = GLES20.glGetAttribLocation(program, "a_Uv")
        GLES20.glVertexAttribPointer(position, 2, GLES20.GL_FLOAT, false, 0, quad)
        GLES20.glVertexAttribPointer(texCoord, 2, GLES20.GL_FLOAT, false, 0, uv)
        GLES20.glEnableVertexAttribArray(position)
        GLES20.glEnableVertexAttribArray(texCoord)
        GLES20.glDrawArrays(GLES20.GL_TRIANGLE_STRIP, 0, 4)
        GLES20.glDisableVertexAttribArray(position)
        GLES20.glDisableVertexAttribArray(texCoord)
        GLES20.glDepthMask(true)
        GLES20.glEnable(GLES20.GL_DEPTH_TEST)
    }
}

/**
 * Draws the render plan the library made: the path through the joints coloured
 * by each sub-trajectory's class (the paper's red, yellow, blue), the frustum
 * positions as dots and the markers as large dots. Positions come from the
 * library as they are; nothing is computed here.
 */
class PlanDrawing {
    private var program = 0
    private val mvp = FloatArray(16)
    private val buffer = floats(3 * 4096)

    /** On the GL thread, once the surface exists. */
    fun create() {
        program = program(
            "uniform mat4 u_Mvp; uniform float u_Size; attribute vec4 a_Position;" +
                "void main() { gl_Position = u_Mvp * a_Position; gl_PointSize = u_Size; }",
            "precision mediump float; uniform vec4 u_Color; void main() { gl_FragColor = u_Color; }"
        )
    }

    /**
     * Draws [plan] and [markers] with the camera's [view] and [projection] matrices; marker `i`
     * is drawn [markerScale]`(i)` times its size (the kineticon's pulse).
     */
    fun draw(plan: RenderPlan, markers: List<Marker>, view: FloatArray, projection: FloatArray, markerScale: (Int) -> Float = { 1f }) {
        Matrix.multiplyMM(mvp, 0, projection, 0, view, 0)
        GLES20.glUseProgram(program)
        GLES20.glUniformMatrix4fv(GLES20.glGetUniformLocation(program, "u_Mvp"), 1, false, mvp, 0)
        GLES20.glLineWidth(8f)
        // Runs of joints of one class, each joined to the previous run so the path stays whole.
        var start = 0
        val joints = plan.joints
        while (start < joints.size) {
            var end = start
            while (end + 1 < joints.size && joints[end + 1].errorClass == joints[start].errorClass) end++
            val from = if (start > 0) start - 1 else start
            shape(GLES20.GL_LINE_STRIP, joints.subList(from, end + 1).map { Triple(it.position.x, it.position.y, it.position.z) }, joints[start].errorClass, 8f)
            start = end + 1
        }
        for (f in plan.frustums) shape(GLES20.GL_POINTS, listOf(Triple(f.pose.px, f.pose.py, f.pose.pz)), f.errorClass, 20f)
        for ((i, m) in markers.withIndex()) {
            shape(GLES20.GL_POINTS, listOf(Triple(m.position.x, m.position.y, m.position.z)), m.errorClass, 60f * markerScale(i))
        }
    }

    /**
     * The venue map layer: surface cells as translucent square tiles coloured by class, path
     * cells as a faint trail of small dots ([VenueView.cellColor]).
     */
    fun drawVenue(cells: List<VenueCell>, view: FloatArray, projection: FloatArray) {
        Matrix.multiplyMM(mvp, 0, projection, 0, view, 0)
        GLES20.glUseProgram(program)
        GLES20.glUniformMatrix4fv(GLES20.glGetUniformLocation(program, "u_Mvp"), 1, false, mvp, 0)
        GLES20.glEnable(GLES20.GL_BLEND)
        GLES20.glBlendFunc(GLES20.GL_SRC_ALPHA, GLES20.GL_ONE_MINUS_SRC_ALPHA)
        for (c in cells) {
            val surface = c.kind == CellKind.SURFACE
            points(GLES20.GL_POINTS, listOf(Triple(c.position.x, c.position.y, c.position.z)),
                VenueView.cellColor(c.kind, c.errorClass), if (surface) 48f else 12f)
        }
        GLES20.glDisable(GLES20.GL_BLEND)
    }

    private fun shape(mode: Int, points: List<Triple<Double, Double, Double>>, errorClass: ErrorClass, size: Float) {
        val c = colour(errorClass)
        points(mode, points, floatArrayOf(c[0], c[1], c[2], 1f), size)
    }

    private fun points(mode: Int, points: List<Triple<Double, Double, Double>>, rgba: FloatArray, size: Float) {
        val n = minOf(points.size, buffer.capacity() / 3)
        buffer.clear()
        for (i in 0 until n) {
            buffer.put(points[i].first.toFloat()).put(points[i].second.toFloat()).put(points[i].third.toFloat())
        }
        buffer.rewind()
        GLES20.glUniform4f(GLES20.glGetUniformLocation(program, "u_Color"), rgba[0], rgba[1], rgba[2], rgba[3])
        GLES20.glUniform1f(GLES20.glGetUniformLocation(program, "u_Size"), size)
        val position = GLES20.glGetAttribLocation(program, "a_Position")
        GLES20.glVertexAttribPointer(position, 3, GLES20.GL_FLOAT, false, 0, buffer)
        GLES20.glEnableVertexAttribArray(position)
        GLES20.glDrawArrays(mode, 0, n)
        GLES20.glDisableVertexAttribArray(position)
    }

    private fun colour(c: ErrorClass): FloatArray = when (c) {
        ErrorClass.HIGH -> floatArrayOf(0.9f, 0.1f, 0.1f)
        ErrorClass.MEDIUM -> floatArrayOf(0.95f, 0.85f, 0.1f)
        ErrorClass.LOW -> floatArrayOf(0.15f, 0.35f, 0.95f)
        ErrorClass.UNKNOWN -> floatArrayOf(0.9f, 0.9f, 0.9f)
    }
}
