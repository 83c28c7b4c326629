package android.widget;
public class ImageView extends android.view.View {
    public ImageView(android.content.Context context) { super(context); throw new RuntimeException("Stub!"); }
    public void setImageBitmap(android.graphics.Bitmap bm) { throw new RuntimeException("Stub!"); }
}
