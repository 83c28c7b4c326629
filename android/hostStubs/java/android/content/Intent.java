package android.content;
public class Intent {
    public Intent() { throw new RuntimeException("Stub!"); }
    public boolean hasExtra(String name) { throw new RuntimeException("Stub!"); }
    public int getIntExtra(String name, int defaultValue) { throw new RuntimeException("Stub!"); }
    public String getStringExtra(String name) { throw new RuntimeException("Stub!"); }
}
