package android.opengl;
public class Matrix {
    public static void multiplyMM(float[] result, int resultOffset, float[] lhs, int lhsOffset, float[] rhs, int rhsOffset) { throw new RuntimeException("Stub!"); }
}
