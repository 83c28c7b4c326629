// Stubs of the UnityEngine API (Unity 2021.3) used by unity-plugin/Runtime.
// They exist only to type-check the package with `mcs` against the real
// API's shapes (names, parameter and return types, static vs instance,
// properties vs fields vs methods; tests/tests/unity_package.rs); nothing here
// runs: every body throws or returns a default. Only what the package uses is
// stubbed, plus UnityEngine.Pose and UnityEngine.Joint, which the package
// does not use but whose names collide with Sitar.Pose and Sitar.Joint: with
// them present the check proves those names still resolve to Sitar's types.
using System;

namespace UnityEngine
{
    public class Object
    {
        public static T Instantiate<T>(T original, Vector3 position, Quaternion rotation) where T : Object { throw null; }
        public static Object Instantiate(Object original, Vector3 position, Quaternion rotation) { throw null; }
        public static void Destroy(Object obj) { throw null; }
        public static void Destroy(Object obj, float t) { throw null; }

        public static implicit operator bool(Object exists) { throw null; }
        public static bool operator ==(Object x, Object y) { throw null; }
        public static bool operator !=(Object x, Object y) { throw null; }
        public override bool Equals(object other) { throw null; }
        public override int GetHashCode() { throw null; }
    }

    public class Component : Object
    {
        public Transform transform { get { throw null; } }
        public GameObject gameObject { get { throw null; } }
        public T GetComponent<T>() { throw null; }
    }

    public class Behaviour : Component { }

    public class MonoBehaviour : Behaviour { }

    public sealed class GameObject : Object
    {
        public Transform transform { get { throw null; } }
        public void SetActive(bool value) { throw null; }
        public T[] GetComponentsInChildren<T>() { throw null; }
    }

    public class Transform : Component
    {
        public Vector3 position { get { throw null; } set { throw null; } }
        public Quaternion rotation { get { throw null; } set { throw null; } }
        public Vector3 localScale { get { throw null; } set { throw null; } }
    }

    public class Renderer : Component
    {
        public Material sharedMaterial { get { throw null; } set { throw null; } }
    }

    public class Material : Object { }

    public class Texture : Object { }

    public class Texture2D : Texture
    {
        public Texture2D(int width, int height) { throw null; }
    }

    public static class ImageConversion
    {
        public static bool LoadImage(this Texture2D tex, byte[] data) { throw null; }
    }

    public struct Vector2
    {
        public float x;
        public float y;
    }

    public struct Vector2Int
    {
        public int x { get { throw null; } set { throw null; } }
        public int y { get { throw null; } set { throw null; } }
    }

    public struct Vector3
    {
        public float x;
        public float y;
        public float z;
        public Vector3(float x, float y, float z) { throw null; }
        public static Vector3 zero { get { throw null; } }
    }

    public struct Quaternion
    {
        public float x;
        public float y;
        public float z;
        public float w;
        public Quaternion(float x, float y, float z, float w) { throw null; }
        public static Quaternion identity { get { throw null; } }
        public static Quaternion Euler(float x, float y, float z) { throw null; }
    }

    /// <summary>Name-collision sentinel (see the header): the real struct has these fields.</summary>
    public struct Pose
    {
        public Vector3 position;
        public Quaternion rotation;
    }

    /// <summary>Name-collision sentinel (see the header): the physics joint component.</summary>
    public class Joint : Component { }

    public struct Mathf
    {
        public static int CeilToInt(float f) { throw null; }
        public static int RoundToInt(float f) { throw null; }
    }

    public static class Debug
    {
        public static void Log(object message) { throw null; }
        public static void LogWarning(object message) { throw null; }
        public static void LogError(object message) { throw null; }
    }

    public class Application
    {
        public static string persistentDataPath { get { throw null; } }
    }

    public enum ScreenOrientation
    {
        Portrait = 1,
        PortraitUpsideDown = 2,
        LandscapeLeft = 3,
        LandscapeRight = 4,
        AutoRotation = 5,
    }

    public sealed class Screen
    {
        public static ScreenOrientation orientation { get { throw null; } set { throw null; } }
        public static int sleepTimeout { get { throw null; } set { throw null; } }
        public static int width { get { throw null; } }
        public static int height { get { throw null; } }
    }

    public class Time
    {
        public static float time { get { throw null; } }
    }

    public class TextAsset : Object
    {
        public string text { get { throw null; } }
    }

    public sealed class Camera : Behaviour
    {
        public float fieldOfView { get { throw null; } set { throw null; } }
    }

    public sealed class SleepTimeout
    {
        public const int NeverSleep = -1;
        public const int SystemSetting = -2;
    }

    public sealed class SerializeField : Attribute { }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public abstract class PropertyAttribute : Attribute { }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = true)]
    public class HeaderAttribute : PropertyAttribute
    {
        public readonly string header;
        public HeaderAttribute(string header) { throw null; }
    }

    [AttributeUsage(AttributeTargets.Field, Inherited = true, AllowMultiple = false)]
    public class TooltipAttribute : PropertyAttribute
    {
        public readonly string tooltip;
        public TooltipAttribute(string tooltip) { throw null; }
    }

    [AttributeUsage(AttributeTargets.Class, AllowMultiple = true, Inherited = true)]
    public sealed class RequireComponent : Attribute
    {
        public RequireComponent(Type requiredComponent) { throw null; }
    }

    // UnityEngine.AndroidJNIModule (the real classes exist on every platform;
    // they only work on Android).
    public class AndroidJavaObject : IDisposable
    {
        internal AndroidJavaObject() { throw null; }
        public AndroidJavaObject(string className, params object[] args) { throw null; }
        public ReturnType Call<ReturnType>(string methodName, params object[] args) { throw null; }
        public ReturnType CallStatic<ReturnType>(string methodName, params object[] args) { throw null; }
        public FieldType GetStatic<FieldType>(string fieldName) { throw null; }
        public void Dispose() { throw null; }
    }

    public class AndroidJavaClass : AndroidJavaObject
    {
        public AndroidJavaClass(string className) { throw null; }
    }
}

namespace UnityEngine.Events
{
    public delegate void UnityAction();

    public abstract class UnityEventBase { }

    public class UnityEvent : UnityEventBase
    {
        public void AddListener(UnityAction call) { throw null; }
        public void RemoveListener(UnityAction call) { throw null; }
    }
}

namespace Unity.Collections
{
    public struct NativeArray<T> : IDisposable where T : struct
    {
        public int Length { get { throw null; } }
        public void Dispose() { throw null; }
    }
}

namespace Unity.Collections.LowLevel.Unsafe
{
    public static class NativeArrayUnsafeUtility
    {
        public static unsafe void* GetUnsafeReadOnlyPtr<T>(this NativeArray<T> nativeArray) where T : struct { throw null; }
    }
}
