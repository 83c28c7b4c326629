package android.view;
public interface WindowManager {
    /** @deprecated API 30 (Context.getDisplay); still what minSdk 24 has. */
    @Deprecated
    Display getDefaultDisplay();
    class LayoutParams extends ViewGroup.LayoutParams {
        public static final int FLAG_KEEP_SCREEN_ON = 0x00000080;
        public LayoutParams() { super(0, 0); throw new RuntimeException("Stub!"); }
    }
}
