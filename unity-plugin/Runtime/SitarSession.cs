// SiTAR for C#: a SafeHandle-owning, exception-raising wrapper over the C ABI
// (NativeMethods.g.cs). No UnityEngine dependency: it also runs on plain Mono
// and .NET (the host test does). No geometry here: it all comes from the
// native render plan and markers.
using System;
using System.Collections.Generic;
using System.Runtime.ConstrainedExecution;
using System.Runtime.InteropServices;
using System.Text;

namespace Sitar
{
    // SitarErrorCode and UploadState are generated from the library's declarations
    // (SitarStatus.g.cs).

    /// <summary>An error reported by the native library; <see cref="Code"/> says which kind.</summary>
    public sealed class SitarException : Exception
    {
        public SitarErrorCode Code { get; }

        public SitarException(SitarErrorCode code, string message) : base(message)
        {
            Code = code;
        }
    }

    /// <summary>World-from-camera pose (metres, unit quaternion) in the session's convention.</summary>
    public struct Pose
    {
        public double Px, Py, Pz, Qx, Qy, Qz, Qw;

        public Pose(double px, double py, double pz, double qx, double qy, double qz, double qw)
        {
            Px = px; Py = py; Pz = pz; Qx = qx; Qy = qy; Qz = qz; Qw = qw;
        }

        internal SitarPose ToNative()
        {
            return new SitarPose { px = Px, py = Py, pz = Pz, qx = Qx, qy = Qy, qz = Qz, qw = Qw };
        }

        internal static Pose FromNative(SitarPose p)
        {
            return new Pose(p.px, p.py, p.pz, p.qx, p.qy, p.qz, p.qw);
        }

        public override string ToString()
        {
            return string.Format("Pose(({0}, {1}, {2}), ({3}, {4}, {5}, {6}))", Px, Py, Pz, Qx, Qy, Qz, Qw);
        }
    }

    /// <summary>Pinhole intrinsics of the depth image, in its pixels.</summary>
    public struct Intrinsics
    {
        public double Fx, Fy, Cx, Cy;

        public Intrinsics(double fx, double fy, double cx, double cy)
        {
            Fx = fx; Fy = fy; Cx = cx; Cy = cy;
        }
    }

    /// <summary>Error class: 0 unknown, 1 low, 2 medium, 3 high.</summary>
    public enum ErrorClass
    {
        Unknown = 0,
        Low = 1,
        Medium = 2,
        High = 3,
    }

    /// <summary>How well the platform tracked the venue's anchor image in one observation.</summary>
    public enum Tracking
    {
        /// <summary>Not tracked (AR Foundation TrackingState.None).</summary>
        None = 0,
        /// <summary>Limited (TrackingState.Limited): recorded, never used for alignment.</summary>
        Limited = 1,
        /// <summary>Fully tracked (TrackingState.Tracking): the observations that align.</summary>
        Full = 2,
    }

    /// <summary>A venue map cell's kind.</summary>
    public enum CellKind
    {
        /// <summary>Where cameras were (sub-trajectory midpoints).</summary>
        Path = 0,
        /// <summary>What cameras looked at (surface points).</summary>
        Surface = 1,
    }

    /// <summary>
    /// A venue map cell in this session's world frame (the layout of the native
    /// SitarVenueCell, so an array of them is filled in place).
    /// </summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct VenueCell
    {
        public double Px, Py, Pz;
        public CellKind Kind;
        public ErrorClass ErrorClass;
        /// <summary>Sessions with a sub-trajectory in the cell.</summary>
        public uint Sessions;
        /// <summary>The cell's error (m): 30 % trimmed mean of its sub-trajectories' errors.</summary>
        public double ErrorM;
    }

    /// <summary>
    /// Where a target is shown: its projection when on screen, else the point on the ellipse
    /// inside the screen's edge in its direction (the layout of the native SitarGuide).
    /// Pixels from the top-left, y down; AngleRad 0 points right, positive clockwise.
    /// </summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Guide
    {
        private int onScreen;
        public double XPx, YPx, AngleRad, DistanceM;
        public bool OnScreen { get { return onScreen != 0; } }
    }

    /// <summary>What Stop reports (counting as in ARCHITECTURE.md).</summary>
    public struct Summary
    {
        public uint Frames, Midpoints, Subtrajectories, DepthSamples;
        public double DurationS, LengthM, MeanDepthM;

        internal static Summary FromNative(SitarSummary s)
        {
            return new Summary
            {
                Frames = s.frames, Midpoints = s.midpoints, Subtrajectories = s.subtrajectories,
                DepthSamples = s.depth_samples, DurationS = s.duration_s, LengthM = s.length_m, MeanDepthM = s.mean_depth_m,
            };
        }
    }

    /// <summary>
    /// A marker: position, warning-sign rotation (local +Y along the normal), surface normal;
    /// ErrorM is in the results' unit (metres, or degrees with pose_relation angle_deg).
    /// </summary>
    public struct Marker
    {
        public double Px, Py, Pz, Qx, Qy, Qz, Qw, Nx, Ny, Nz;
        public ErrorClass ErrorClass;
        public uint Subtrajectory;
        public double ErrorM;
    }

    /// <summary>
    /// The interval of a calibrated result window, in the results' unit (metres, or degrees
    /// with pose_relation angle_deg): the true error lies in [LowerM, UpperM] with the
    /// calibration's coverage (e.g. 80 %). A calibration belongs to one SLAM system and
    /// playback device. RawM is the window's uncalibrated estimate, null when the results do
    /// not give it.
    /// </summary>
    public struct ErrorBounds
    {
        public double LowerM, UpperM;
        public double? RawM;
    }

    /// <summary>Where results come from ("source").</summary>
    public enum ResultSource
    {
        /// <summary>No results, or results that do not say (legacy CSV).</summary>
        Unknown = 0,
        /// <summary>The walk itself, from a calibration: on the phone at Stop, or by the backend at upload.</summary>
        Walk = 1,
        /// <summary>Replays of the recording on playback devices.</summary>
        Replays = 2,
    }

    /// <summary>Which error results estimate ("target").</summary>
    public enum ResultTarget
    {
        /// <summary>Not said (uncalibrated results, legacy CSV) or no results.</summary>
        Unknown = 0,
        /// <summary>The error of the live run: the user's own walk.</summary>
        Live = 1,
        /// <summary>The error expected at each place (the mean over runs).</summary>
        Expected = 2,
    }

    /// <summary>
    /// Where the loaded results come from: Source, Target, the number of Runs (the walk and its
    /// replays; null when not said) and whether the calibration's runs predict the error at all
    /// (Informative; null when not said).
    /// </summary>
    public struct Provenance
    {
        public ResultSource Source;
        public ResultTarget Target;
        public uint? Runs;
        public bool? Informative;

        /// <summary>
        /// The calibration says its runs do not predict this system's error: show the colours
        /// with "this system's error cannot be told from its runs: colours are a guess".
        /// </summary>
        public bool IsGuess { get { return Informative == false; } }
    }

    /// <summary>The result of one sub-trajectory: error (in the results' unit; null when no result window is near) and class.</summary>
    public struct SubtrajectoryResult
    {
        public uint Subtrajectory;
        public double? ErrorM;
        public ErrorClass ErrorClass;
    }

    /// <summary>Likely causes of a sub-trajectory's error (bits of SitarEvidence.causes).</summary>
    [Flags]
    public enum Causes : uint
    {
        None = 0,
        LowTexture = 1,
        Dark = 2,
        Overexposed = 4,
        Blur = 8,
        FastMotion = 16,
        FarSurface = 32,
        NoDepth = 64,
    }

    /// <summary>What the camera saw at a sub-trajectory's midpoint, how it moved, its depth, likely causes.</summary>
    public struct Evidence
    {
        public uint Subtrajectory;
        public bool HasImage;
        public double MeanBrightness, ContrastStd, LaplacianVar, CornersPer10k, SaturatedShare;
        public double LinearSpeedMS, AngularSpeedDegS;
        public bool DepthGiven, DepthValid;
        public double DistanceM, DepthValidShare;
        public Causes Causes;
        public uint ThumbnailWidth, ThumbnailHeight;

        internal static Evidence FromNative(SitarEvidence e)
        {
            return new Evidence
            {
                Subtrajectory = e.subtrajectory, HasImage = e.has_image != 0,
                MeanBrightness = e.mean_brightness, ContrastStd = e.contrast_std, LaplacianVar = e.laplacian_var,
                CornersPer10k = e.corners_per_10k, SaturatedShare = e.saturated_share,
                LinearSpeedMS = e.linear_speed_m_s, AngularSpeedDegS = e.angular_speed_deg_s,
                DepthGiven = e.depth_given != 0, DepthValid = e.depth_valid != 0,
                DistanceM = e.distance_m, DepthValidShare = e.depth_valid_share,
                Causes = (Causes)e.causes, ThumbnailWidth = e.thumbnail_width, ThumbnailHeight = e.thumbnail_height,
            };
        }
    }

    /// <summary>A path segment: a cylinder of Length centred at C, local +Y along the path.</summary>
    public struct Segment
    {
        public double Cx, Cy, Cz, Qx, Qy, Qz, Qw, Length;
        public uint Subtrajectory;
        public ErrorClass ErrorClass;
    }

    /// <summary>A sphere between segments.</summary>
    public struct Joint
    {
        public double Px, Py, Pz;
        public uint Subtrajectory;
        public ErrorClass ErrorClass;
    }

    /// <summary>A camera frustum to draw.</summary>
    public struct Frustum
    {
        public Pose Pose;
        public uint Subtrajectory;
        public ErrorClass ErrorClass;
    }

    /// <summary>Everything to draw the trajectory, each item with its class.</summary>
    public sealed class RenderPlan
    {
        public Segment[] Segments;
        public Joint[] Joints;
        public Frustum[] Frustums;
        public Pose? Start;
        public Pose? Stop;
    }

    /// <summary>A snapshot of an upload job.</summary>
    public struct UploadProgress
    {
        public UploadState State;
        public SitarErrorCode ErrorCode;
        public double Progress;
        /// <summary>Seconds to go as the server estimates; negative if unknown.</summary>
        public double EtaS;
        public ulong BytesSent, BytesTotal;
        public uint TrialsDone, TrialsTotal;
        /// <summary>Incremented whenever (progressive or final) results were loaded into the session.</summary>
        public uint ResultsRevision;
        public uint ResultsTrials;

        public bool Finished { get { return State >= UploadState.Done; } }
    }

    /// <summary>
    /// Owns one native handle (an id, not a pointer; it fits any platform) and
    /// frees it exactly once, also from the finalizer.
    /// </summary>
    internal sealed class SitarHandle : SafeHandle
    {
        internal delegate int Free(ulong id);

        private readonly Free free;
        private ulong id;

        internal SitarHandle(ulong id, Free free) : base(IntPtr.Zero, true)
        {
            this.id = id;
            this.free = free;
            SetHandle(new IntPtr(1));
        }

        /// <summary>The id, or 0 once closed (the native side then reports INVALID_HANDLE).</summary>
        internal ulong Id { get { return IsClosed ? 0UL : id; } }

        public override bool IsInvalid { get { return handle == IntPtr.Zero; } }

        [ReliabilityContract(Consistency.WillNotCorruptState, Cer.Success)]
        protected override bool ReleaseHandle()
        {
            ulong h = id;
            id = 0;
            return h == 0 || free(h) == 0;
        }
    }

    internal static unsafe class Native
    {
        internal static void Check(int status)
        {
            if (status != 0)
            {
                throw new SitarException((SitarErrorCode)status, LastError());
            }
        }

        internal static string LastError()
        {
            UIntPtr len;
            NativeMethods.sitar_last_error(null, UIntPtr.Zero, &len);
            byte[] buf = new byte[(int)len.ToUInt64() + 1];
            fixed (byte* p = buf)
            {
                NativeMethods.sitar_last_error(p, new UIntPtr((ulong)buf.Length), &len);
            }
            return Encoding.UTF8.GetString(buf, 0, (int)len.ToUInt64());
        }

        /// <summary>NUL-terminated UTF-8; null stays null.</summary>
        internal static byte[] Utf8(string s)
        {
            return s == null ? null : Encoding.UTF8.GetBytes(s + "\0");
        }

        internal delegate int TextCall(byte* buf, UIntPtr cap, UIntPtr* outLen);

        /// <summary>Calls a text-output function, growing the buffer as needed.</summary>
        internal static string Text(TextCall call)
        {
            UIntPtr len;
            int st = call(null, UIntPtr.Zero, &len);
            while (true)
            {
                if (st != (int)SitarErrorCode.BufferTooSmall) Check(st);
                byte[] buf = new byte[(int)len.ToUInt64() + 1];
                fixed (byte* p = buf)
                {
                    st = call(p, new UIntPtr((ulong)buf.Length), &len);
                }
                if (st == 0) return Encoding.UTF8.GetString(buf, 0, (int)len.ToUInt64());
            }
        }

        /// <summary>Calls an array-output function with buf (null = size query) and its length as capacity.</summary>
        internal delegate int ArrayCall<T>(T[] buf, UIntPtr* outLen);

        internal static UIntPtr Cap<T>(T[] buf)
        {
            return new UIntPtr((ulong)(buf == null ? 0 : buf.Length));
        }
    }

    /// <summary>
    /// One recording session: Start, Frame (every camera frame), Depth (at
    /// midpoints), Stop, Upload, then ErrorAt / Markers / GetRenderPlan.
    /// Every method throws <see cref="SitarException"/> on error; after
    /// Dispose calls throw one with code InvalidHandle. Thread-safe.
    /// </summary>
    public sealed unsafe class SitarSession : IDisposable
    {
        /// <summary>Frame flag: a midpoint, give the depth image now.</summary>
        public const uint Midpoint = 1;
        /// <summary>Frame flag: a sub-trajectory is complete.</summary>
        public const uint Endpoint = 2;

        private readonly SitarHandle handle;

        /// <summary>A session from its JSON config (every key optional; "{}" = defaults).</summary>
        public SitarSession(string configJson = "{}")
        {
            ulong h;
            fixed (byte* c = Native.Utf8(configJson))
            {
                Native.Check(NativeMethods.sitar_session_new(c, &h));
            }
            handle = new SitarHandle(h, NativeMethods.sitar_session_free);
        }

        private SitarSession(ulong h)
        {
            handle = new SitarHandle(h, NativeMethods.sitar_session_free);
        }

        /// <summary>The native library version.</summary>
        public static string Version
        {
            get { return Marshal.PtrToStringAnsi((IntPtr)NativeMethods.sitar_version()); }
        }

        /// <summary>Loads a saved session folder.</summary>
        public static SitarSession Load(string dir)
        {
            ulong h;
            fixed (byte* d = Native.Utf8(dir))
            {
                Native.Check(NativeMethods.sitar_session_load(d, &h));
            }
            return new SitarSession(h);
        }

        internal ulong Id { get { return handle.Id; } }

        public void Start(long tNs, Pose pose)
        {
            SitarPose p = pose.ToNative();
            Native.Check(NativeMethods.sitar_session_start(Id, tNs, &p));
        }

        /// <summary>One camera frame (allocation-free); returns flags (<see cref="Midpoint"/>, <see cref="Endpoint"/>).</summary>
        public uint Frame(long tNs, Pose pose)
        {
            SitarPose p = pose.ToNative();
            uint flags;
            Native.Check(NativeMethods.sitar_session_frame(Id, tNs, &p, &flags));
            return flags;
        }

        /// <summary>
        /// The depth image (16-bit millimetres, sensor orientation) for the last
        /// midpoint; <paramref name="data"/> points at (height-1)*rowStrideBytes + width*2 bytes.
        /// </summary>
        public void Depth(IntPtr data, int width, int height, int rowStrideBytes, Intrinsics k, int displayRotation)
        {
            SitarIntrinsics ki = new SitarIntrinsics { fx = k.Fx, fy = k.Fy, cx = k.Cx, cy = k.Cy };
            Native.Check(NativeMethods.sitar_session_depth(Id, (ushort*)data, width, height, rowStrideBytes, &ki, displayRotation));
        }

        /// <summary>As <see cref="Depth(IntPtr,int,int,int,Intrinsics,int)"/> from a managed array (checked for size).</summary>
        public void Depth(ushort[] data, int width, int height, int rowStrideBytes, Intrinsics k, int displayRotation)
        {
            if (data == null) throw new SitarException(SitarErrorCode.Null, "argument `data` is null");
            long needed = width > 0 && height > 0 ? ((long)(height - 1) * rowStrideBytes + (long)width * 2) / 2 : 0;
            if (data.LongLength < needed)
            {
                throw new SitarException(SitarErrorCode.InvalidArgument, string.Format(
                    "invalid argument `data`: {0} samples; a {1}x{2} image with row stride {3} bytes needs {4}",
                    data.LongLength, width, height, rowStrideBytes, needed));
            }
            fixed (ushort* p = data)
            {
                Depth((IntPtr)p, width, height, rowStrideBytes, k, displayRotation);
            }
        }

        /// <summary>
        /// The camera's luminance plane (XRCpuImage Y plane, sensor orientation) for the latest
        /// midpoint: give it when Frame returns the midpoint bit, with that frame's image;
        /// <paramref name="data"/> points at (height-1)*rowStrideBytes + width bytes. A no-op
        /// with "images": false in the config.
        /// </summary>
        public void Image(IntPtr data, int width, int height, int rowStrideBytes, int displayRotation)
        {
            Native.Check(NativeMethods.sitar_session_image(Id, (byte*)data, width, height, rowStrideBytes, displayRotation));
        }

        /// <summary>As <see cref="Image(IntPtr,int,int,int,int)"/> from a managed array (checked for size).</summary>
        public void Image(byte[] data, int width, int height, int rowStrideBytes, int displayRotation)
        {
            if (data == null) throw new SitarException(SitarErrorCode.Null, "argument `luma` is null");
            long needed = width > 0 && height > 0 ? (long)(height - 1) * rowStrideBytes + width : 0;
            if (data.LongLength < needed)
            {
                throw new SitarException(SitarErrorCode.InvalidArgument, string.Format(
                    "invalid argument `luma`: {0} bytes; a {1}x{2} plane with row stride {3} needs {4}",
                    data.LongLength, width, height, rowStrideBytes, needed));
            }
            fixed (byte* p = data)
            {
                Image((IntPtr)p, width, height, rowStrideBytes, displayRotation);
            }
        }

        /// <summary>What the camera saw at sub-trajectory k, how it moved, its depth and likely causes.</summary>
        public Evidence SubtrajectoryEvidence(uint k)
        {
            SitarEvidence e;
            Native.Check(NativeMethods.sitar_session_subtrajectory_evidence(Id, k, &e));
            return Evidence.FromNative(e);
        }

        /// <summary>The greyscale JPEG thumbnail of sub-trajectory k (empty without an image), e.g. for Texture2D.LoadImage.</summary>
        public byte[] Thumbnail(uint k)
        {
            ulong id = Id;
            return Items<byte>((b, l) => { fixed (byte* p = b) return NativeMethods.sitar_session_thumbnail(id, k, p, Native.Cap(b), l); });
        }

        public Summary Stop(long tNs, Pose pose)
        {
            SitarPose p = pose.ToNative();
            SitarSummary s;
            Native.Check(NativeMethods.sitar_session_stop(Id, tNs, &p, &s));
            return Summary.FromNative(s);
        }

        public Summary GetSummary()
        {
            SitarSummary s;
            Native.Check(NativeMethods.sitar_session_summary(Id, &s));
            return Summary.FromNative(s);
        }

        /// <summary>
        /// Loads results: legacy CSV (start,error) or JSON. Results for another window length
        /// than the config's subtrajectory_frames, or another pose_relation, are refused
        /// (InvalidArgument).
        /// </summary>
        public void LoadResults(string csvOrJson)
        {
            fixed (byte* t = Native.Utf8(csvOrJson))
            {
                Native.Check(NativeMethods.sitar_session_load_results(Id, t));
            }
        }

        /// <summary>
        /// Class and error (in the results' unit; null if no result window is near) at a
        /// timestamp. The class is that of the value the config's classify_by picks: the error
        /// ("estimate", default) or, with "upper", the window's upper bound where the results
        /// give one.
        /// </summary>
        public ErrorClass ErrorAt(long tNs, out double? errorM)
        {
            int cls;
            double e;
            Native.Check(NativeMethods.sitar_session_error_at(Id, tNs, &cls, &e));
            errorM = double.IsNaN(e) ? (double?)null : e;
            return (ErrorClass)cls;
        }

        /// <summary>
        /// The interval of the result window ErrorAt finds at tNs, when the loaded results are
        /// calibrated; null when no window is near, no results are loaded, or they are not
        /// calibrated.
        /// </summary>
        public ErrorBounds? BoundsAt(long tNs)
        {
            int present;
            double lower, upper, raw;
            Native.Check(NativeMethods.sitar_session_bounds_at(Id, tNs, &present, &lower, &upper, &raw));
            if (present == 0) return null;
            return new ErrorBounds { LowerM = lower, UpperM = upper, RawM = double.IsNaN(raw) ? (double?)null : raw };
        }

        /// <summary>The name of the calibration of the loaded results; null when they are not calibrated.</summary>
        public string ResultsCalibration()
        {
            ulong id = Id;
            string name = Native.Text((b, c, l) => NativeMethods.sitar_session_results_calibration(id, b, c, l));
            return name.Length == 0 ? null : name;
        }

        /// <summary>
        /// Takes a calibration (the JSON file sitar calibrate writes, e.g. a bundled TextAsset's
        /// text) so the walk is coloured the moment it stops, offline: every sub-trajectory gets
        /// the calibrated error and interval of the walk alone, the markers their places. Given
        /// after Stop it colours at once, unless the backend's results are loaded; the backend's
        /// results replace the walk's when they arrive (ResultsProvenance says which). Malformed
        /// JSON is Parse; a calibration for another window (subtrajectory_frames) or
        /// pose_relation, or without a model for one run, InvalidArgument, naming what differs.
        /// A refused calibration changes nothing.
        /// </summary>
        public void SetCalibration(string json)
        {
            fixed (byte* t = Native.Utf8(json))
            {
                Native.Check(NativeMethods.sitar_session_set_calibration(Id, t));
            }
        }

        /// <summary>Where the loaded results come from: the walk or replays, how many runs, and whether the colours are a guess.</summary>
        public Provenance ResultsProvenance()
        {
            int source, target, informative;
            uint runs;
            Native.Check(NativeMethods.sitar_session_results_provenance(Id, &source, &target, &runs, &informative));
            return new Provenance
            {
                Source = (ResultSource)source,
                Target = (ResultTarget)target,
                Runs = runs == 0 ? (uint?)null : runs,
                Informative = informative < 0 ? (bool?)null : informative == 1,
            };
        }

        public ErrorClass SubtrajectoryClass(uint k)
        {
            int cls;
            Native.Check(NativeMethods.sitar_session_subtrajectory_class(Id, k, &cls));
            return (ErrorClass)cls;
        }

        public bool ResultsUnreliable()
        {
            int v;
            Native.Check(NativeMethods.sitar_session_results_unreliable(Id, &v));
            return v != 0;
        }

        private static T[] Items<T>(Native.ArrayCall<T> call)
        {
            UIntPtr len;
            int st = call(null, &len);
            while (true)
            {
                if (st == 0) return new T[0];
                if (st != (int)SitarErrorCode.BufferTooSmall) Native.Check(st);
                T[] items = new T[(int)len.ToUInt64()];
                st = call(items, &len);
                if (st == 0) return items;
            }
        }

        /// <summary>The markers (needs results).</summary>
        public Marker[] Markers()
        {
            ulong id = Id;
            SitarMarker[] raw = Items<SitarMarker>((b, l) => { fixed (SitarMarker* p = b) return NativeMethods.sitar_session_markers(id, p, Native.Cap(b), l); });
            Marker[] markers = new Marker[raw.Length];
            for (int i = 0; i < raw.Length; i++)
            {
                SitarMarker m = raw[i];
                markers[i] = new Marker
                {
                    Px = m.px, Py = m.py, Pz = m.pz, Qx = m.qx, Qy = m.qy, Qz = m.qz, Qw = m.qw,
                    Nx = m.nx, Ny = m.ny, Nz = m.nz, ErrorClass = (ErrorClass)m.error_class,
                    Subtrajectory = m.subtrajectory, ErrorM = m.error_m,
                };
            }
            return markers;
        }

        /// <summary>Every sub-trajectory's error and class, in order (unknown before results arrive).</summary>
        public SubtrajectoryResult[] Results()
        {
            ulong id = Id;
            SitarSubtrajectoryResult[] raw = Items<SitarSubtrajectoryResult>((b, l) => { fixed (SitarSubtrajectoryResult* p = b) return NativeMethods.sitar_session_subtrajectory_results(id, p, Native.Cap(b), l); });
            SubtrajectoryResult[] results = new SubtrajectoryResult[raw.Length];
            for (int i = 0; i < raw.Length; i++)
            {
                results[i] = new SubtrajectoryResult
                {
                    Subtrajectory = raw[i].subtrajectory,
                    ErrorM = double.IsNaN(raw[i].error_m) ? (double?)null : raw[i].error_m,
                    ErrorClass = (ErrorClass)raw[i].error_class,
                };
            }
            return results;
        }

        /// <summary>What to draw: segments, joints, frustums, start and stop.</summary>
        public RenderPlan GetRenderPlan()
        {
            ulong id = Id;
            SitarSegment[] segs = Items<SitarSegment>((b, l) => { fixed (SitarSegment* p = b) return NativeMethods.sitar_session_segments(id, p, Native.Cap(b), l); });
            SitarJoint[] joints = Items<SitarJoint>((b, l) => { fixed (SitarJoint* p = b) return NativeMethods.sitar_session_joints(id, p, Native.Cap(b), l); });
            SitarFrustum[] frus = Items<SitarFrustum>((b, l) => { fixed (SitarFrustum* p = b) return NativeMethods.sitar_session_frustums(id, p, Native.Cap(b), l); });
            SitarPose start, stop;
            uint mask;
            Native.Check(NativeMethods.sitar_session_plan_ends(id, &start, &stop, &mask));
            RenderPlan plan = new RenderPlan
            {
                Segments = new Segment[segs.Length],
                Joints = new Joint[joints.Length],
                Frustums = new Frustum[frus.Length],
                Start = (mask & 1) != 0 ? Pose.FromNative(start) : (Pose?)null,
                Stop = (mask & 2) != 0 ? Pose.FromNative(stop) : (Pose?)null,
            };
            for (int i = 0; i < segs.Length; i++)
            {
                SitarSegment s = segs[i];
                plan.Segments[i] = new Segment
                {
                    Cx = s.cx, Cy = s.cy, Cz = s.cz, Qx = s.qx, Qy = s.qy, Qz = s.qz, Qw = s.qw, Length = s.length,
                    Subtrajectory = s.subtrajectory, ErrorClass = (ErrorClass)s.error_class,
                };
            }
            for (int i = 0; i < joints.Length; i++)
            {
                SitarJoint j = joints[i];
                plan.Joints[i] = new Joint { Px = j.px, Py = j.py, Pz = j.pz, Subtrajectory = j.subtrajectory, ErrorClass = (ErrorClass)j.error_class };
            }
            for (int i = 0; i < frus.Length; i++)
            {
                plan.Frustums[i] = new Frustum { Pose = Pose.FromNative(frus[i].pose), Subtrajectory = frus[i].subtrajectory, ErrorClass = (ErrorClass)frus[i].error_class };
            }
            return plan;
        }

        /// <summary>
        /// An observation of the venue's anchor image: the pose AR Foundation reports for the
        /// ARTrackedImage (world-from-image; image +X to its right) and its tracking state.
        /// An empty or over-long id (> 64 bytes), a non-finite pose or an unknown tracking
        /// value is InvalidArgument; before Start or after Stop InvalidState.
        /// </summary>
        public void Anchor(long tNs, string anchorId, Pose imagePose, Tracking tracking)
        {
            SitarPose p = imagePose.ToNative();
            fixed (byte* a = Native.Utf8(anchorId))
            {
                Native.Check(NativeMethods.sitar_session_anchor(Id, tNs, a, &p, (int)tracking));
            }
        }

        /// <summary>Loads the venue's map.json; the session is aligned once the anchor is fully tracked.</summary>
        public void LoadVenue(string mapJson)
        {
            fixed (byte* t = Native.Utf8(mapJson))
            {
                Native.Check(NativeMethods.sitar_session_load_venue(Id, t));
            }
        }

        /// <summary>
        /// Fills <paramref name="buffer"/> with the venue's cells in this session's world frame
        /// and returns their number; when it is larger than the buffer nothing is written (grow
        /// the buffer and call again). No allocation. InvalidState before the anchor is fully
        /// tracked.
        /// </summary>
        public int VenueCells(VenueCell[] buffer)
        {
            UIntPtr len;
            int st;
            fixed (VenueCell* p = buffer)
            {
                st = NativeMethods.sitar_session_venue_cells(Id, (SitarVenueCell*)p, Native.Cap(buffer), &len);
            }
            if (st != (int)SitarErrorCode.BufferTooSmall) Native.Check(st);
            return (int)len.ToUInt64();
        }

        /// <summary>
        /// Where each marker (Markers() order), then each high venue surface cell, is shown on
        /// a widthPx × heightPx screen seen by <paramref name="camera"/> (the display-oriented
        /// camera pose) with vertical field of view vfovDeg; off-screen targets are pinned to
        /// the ellipse marginPx inside the edges. Fills <paramref name="buffer"/> and returns
        /// the number of targets (nothing written when it exceeds the buffer). No allocation.
        /// </summary>
        public int Guide(Pose camera, double vfovDeg, int widthPx, int heightPx, double marginPx, Guide[] buffer)
        {
            SitarPose c = camera.ToNative();
            UIntPtr len;
            int st;
            fixed (Guide* p = buffer)
            {
                st = NativeMethods.sitar_session_guide(Id, &c, vfovDeg, widthPx, heightPx, marginPx, (SitarGuide*)p, Native.Cap(buffer), &len);
            }
            if (st != (int)SitarErrorCode.BufferTooSmall) Native.Check(st);
            return (int)len.ToUInt64();
        }

        /// <summary>The logged poses as TUM text (integer nanoseconds).</summary>
        public string TrajectoryTum()
        {
            ulong id = Id;
            return Native.Text((b, c, l) => NativeMethods.sitar_session_trajectory_tum(id, b, c, l));
        }

        /// <summary>Saves the session folder.</summary>
        public void Save(string dir)
        {
            fixed (byte* d = Native.Utf8(dir))
            {
                Native.Check(NativeMethods.sitar_session_save(Id, d));
            }
        }

        /// <summary>
        /// Writes the scene as a glTF 2.0 binary file (.glb): trajectory by class, frustums,
        /// markers, surface points, in glTF's frame (glTFast converts it back to Unity's).
        /// </summary>
        public void ExportGltf(string path)
        {
            fixed (byte* p = Native.Utf8(path))
            {
                Native.Check(NativeMethods.sitar_session_export_gltf(Id, p));
            }
        }

        /// <summary>
        /// Uploads the recording in the background; results are loaded into this
        /// session when the server is done. Options JSON: server_url (else the
        /// config's), server_token (the backend's access token), server_cert_sha256 (pins
        /// the backend's TLS certificate by its SHA-256 fingerprint; a different one fails
        /// the job with SITAR_ERR_NETWORK), trials, setting, playback, poll_interval_ms, session_id (continue
        /// that server session, e.g. a failed job's ServerId(): the upload resumes),
        /// window_frames and pose_relation (default: the config's subtrajectory_frames and
        /// pose_relation; other values are refused).
        /// </summary>
        public UploadJob Upload(string recordingPath, string optionsJson = null)
        {
            ulong job;
            fixed (byte* r = Native.Utf8(recordingPath))
            fixed (byte* o = Native.Utf8(optionsJson))
            {
                Native.Check(NativeMethods.sitar_upload_start(Id, r, o, &job));
            }
            return new UploadJob(job);
        }

        /// <summary>Frees the native session exactly once; calling it again is harmless.</summary>
        public void Dispose()
        {
            handle.Dispose();
        }
    }

    /// <summary>A background upload; Dispose frees the handle and cancels a running job.</summary>
    public sealed unsafe class UploadJob : IDisposable
    {
        private readonly SitarHandle handle;

        internal UploadJob(ulong id)
        {
            handle = new SitarHandle(id, NativeMethods.sitar_upload_free);
        }

        /// <summary>A snapshot; never blocks on the network.</summary>
        public UploadProgress Progress()
        {
            SitarJobProgress p;
            Native.Check(NativeMethods.sitar_upload_progress(handle.Id, &p));
            return new UploadProgress
            {
                State = (UploadState)p.state, ErrorCode = (SitarErrorCode)p.error_code, Progress = p.progress,
                EtaS = p.eta_s, BytesSent = p.bytes_sent, BytesTotal = p.bytes_total, TrialsDone = p.trials_done,
                TrialsTotal = p.trials_total, ResultsRevision = p.results_revision, ResultsTrials = p.results_trials,
            };
        }

        /// <summary>Why the job failed ("" otherwise).</summary>
        public string Message()
        {
            ulong id = handle.Id;
            return Native.Text((b, c, l) => NativeMethods.sitar_upload_message(id, b, c, l));
        }

        /// <summary>The server's session id ("" until created).</summary>
        public string ServerId()
        {
            ulong id = handle.Id;
            return Native.Text((b, c, l) => NativeMethods.sitar_upload_server_id(id, b, c, l));
        }

        /// <summary>Cancels: the state is Cancelled at once.</summary>
        public void Cancel()
        {
            Native.Check(NativeMethods.sitar_upload_cancel(handle.Id));
        }

        public void Dispose()
        {
            handle.Dispose();
        }
    }

    /// <summary>The playback-device logger: logs every frame, writes trajectory_N.txt.</summary>
    public sealed unsafe class PlaybackLogger : IDisposable
    {
        private readonly SitarHandle handle;

        public PlaybackLogger(string configJson = "{}")
        {
            ulong h;
            fixed (byte* c = Native.Utf8(configJson))
            {
                Native.Check(NativeMethods.sitar_playback_new(c, &h));
            }
            handle = new SitarHandle(h, NativeMethods.sitar_playback_free);
        }

        public void Log(long tNs, Pose pose)
        {
            SitarPose p = pose.ToNative();
            Native.Check(NativeMethods.sitar_playback_log(handle.Id, tNs, &p));
        }

        public ulong Count
        {
            get
            {
                UIntPtr n;
                Native.Check(NativeMethods.sitar_playback_len(handle.Id, &n));
                return n.ToUInt64();
            }
        }

        public string Tum()
        {
            ulong id = handle.Id;
            return Native.Text((b, c, l) => NativeMethods.sitar_playback_tum(id, b, c, l));
        }

        /// <summary>Writes dir/trajectory_index.txt (creating dir).</summary>
        public void Write(string dir, uint index)
        {
            fixed (byte* d = Native.Utf8(dir))
            {
                Native.Check(NativeMethods.sitar_playback_write(handle.Id, d, index));
            }
        }

        public void Dispose()
        {
            handle.Dispose();
        }
    }
}
