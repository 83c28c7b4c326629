package android.view;
public class View {
    public View(android.content.Context context) { throw new RuntimeException("Stub!"); }
    public void setOnClickListener(OnClickListener l) { throw new RuntimeException("Stub!"); }
    public static final int VISIBLE = 0x00000000;
    public static final int INVISIBLE = 0x00000004;
    public void setVisibility(int visibility) { throw new RuntimeException("Stub!"); }
    public void setX(float x) { throw new RuntimeException("Stub!"); }
    public void setY(float y) { throw new RuntimeException("Stub!"); }
    public void setRotation(float rotation) { throw new RuntimeException("Stub!"); }
    public void setEnabled(boolean enabled) { throw new RuntimeException("Stub!"); }
    public void setBackgroundColor(int color) { throw new RuntimeException("Stub!"); }
    public interface OnClickListener {
        void onClick(View v);
    }
}
