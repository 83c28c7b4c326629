package android.opengl;
public class GLSurfaceView extends android.view.View {
    public static final int RENDERMODE_CONTINUOUSLY = 1;
    public GLSurfaceView(android.content.Context context) { super(context); throw new RuntimeException("Stub!"); }
    public void setPreserveEGLContextOnPause(boolean preserveOnPause) { throw new RuntimeException("Stub!"); }
    public void setEGLContextClientVersion(int version) { throw new RuntimeException("Stub!"); }
    public void setEGLConfigChooser(int redSize, int greenSize, int blueSize, int alphaSize, int depthSize, int stencilSize) { throw new RuntimeException("Stub!"); }
    public void setRenderer(Renderer renderer) { throw new RuntimeException("Stub!"); }
    public void setRenderMode(int renderMode) { throw new RuntimeException("Stub!"); }
    public void onPause() { throw new RuntimeException("Stub!"); }
    public void onResume() { throw new RuntimeException("Stub!"); }
    public interface Renderer {
        void onSurfaceCreated(javax.microedition.khronos.opengles.GL10 gl, javax.microedition.khronos.egl.EGLConfig config);
        void onSurfaceChanged(javax.microedition.khronos.opengles.GL10 gl, int width, int height);
        void onDrawFrame(javax.microedition.khronos.opengles.GL10 gl);
    }
}
