package android.app;
public class Activity extends android.view.ContextThemeWrapper {
    public Activity() { throw new RuntimeException("Stub!"); }
    protected void onCreate(android.os.Bundle savedInstanceState) { throw new RuntimeException("Stub!"); }
    protected void onNewIntent(android.content.Intent intent) { throw new RuntimeException("Stub!"); }
    protected void onResume() { throw new RuntimeException("Stub!"); }
    protected void onPause() { throw new RuntimeException("Stub!"); }
    protected void onDestroy() { throw new RuntimeException("Stub!"); }
    public android.content.Intent getIntent() { throw new RuntimeException("Stub!"); }
    public void setIntent(android.content.Intent newIntent) { throw new RuntimeException("Stub!"); }
    public android.view.Window getWindow() { throw new RuntimeException("Stub!"); }
    public android.view.WindowManager getWindowManager() { throw new RuntimeException("Stub!"); }
    public void setContentView(android.view.View view) { throw new RuntimeException("Stub!"); }
    public final void runOnUiThread(Runnable action) { throw new RuntimeException("Stub!"); }
    public final void requestPermissions(String[] permissions, int requestCode) { throw new RuntimeException("Stub!"); }
    public void onRequestPermissionsResult(int requestCode, String[] permissions, int[] grantResults) { throw new RuntimeException("Stub!"); }
}
