package android.content;
public abstract class Context {
    public static final String CAMERA_SERVICE = "camera";
    public abstract Context getApplicationContext();
    public abstract Object getSystemService(String name);
    public abstract android.content.res.AssetManager getAssets();
    public abstract java.io.File getExternalFilesDir(String type);
    public abstract int checkSelfPermission(String permission);
}
