// The user-device MonoBehaviour (replaces the original DrawTrajectory.cs):
// Start/Stop buttons, ARCore recording, one Frame call per camera frame, depth
// from AROcclusionManager CPU images at midpoints, background upload with a
// progress text, then drawing the native render plan and markers with the
// prefabs. No geometry here: positions, rotations, lengths and classes all
// come from libsitar.
using System;
using System.Collections.Generic;
using System.IO;
using Unity.Collections.LowLevel.Unsafe;
using UnityEngine;
using UnityEngine.UI;
using UnityEngine.XR.ARFoundation;
using UnityEngine.XR.ARSubsystems;
#if UNITY_ANDROID
using UnityEngine.XR.ARCore;
#endif

namespace Sitar.Unity
{
    /// <summary>How results are shown (the paper's three styles).</summary>
    public enum VisualizationStyle
    {
        TrajectoryOnly,
        ExclamationPoints,
        WarningSigns,
    }

    [RequireComponent(typeof(ARSession))]
    public sealed class SitarRecorder : MonoBehaviour
    {
        [Header("AR")]
        [SerializeField] ARCameraManager cameraManager;
        [SerializeField] AROcclusionManager occlusionManager;
        [Tooltip("The AR camera whose transform is the device pose.")]
        public Transform arCamera;

        [Header("Backend")]
        public string serverUrl = "http://192.168.0.10:8000";
        [Tooltip("The backend's app token: `sitar token create --data DIR --role app --name NAME`.")]
        public string serverToken = "";
        [Tooltip("With an https:// server URL and a self-signed certificate: the SHA-256 fingerprint `sitar serve --tls` prints (AB:CD:…). Empty: the platform's roots.")]
        public string serverCertSha256 = "";
        public int trials = 10;
        public string setting = "trim_mean_30";
        public string playback = "adb";

        [Header("Estimate from the walk")]
        [Tooltip("Optional: the calibration file `sitar calibrate` wrote for this app's SLAM system and device (import it as a .json TextAsset). With it the walk is coloured the moment it stops, offline; the backend's results replace that when they arrive.")]
        public TextAsset calibration;
        [Tooltip("Optional: says where the colours come from (your walk, or replays) and when they are a guess.")]
        public Text resultsSource;

        [Header("Prefabs (as in the original DrawTrajectory)")]
        public GameObject startPrefab;
        public GameObject stopPrefab;
        public GameObject cylinderPrefab;
        public GameObject jointPrefab;
        public GameObject frustumPrefab;
        [Tooltip("Exclamation point, high error.")] public GameObject errorAreaHighPrefab;
        [Tooltip("Exclamation point, medium error.")] public GameObject errorAreaMediumPrefab;
        [Tooltip("Warning sign, high error.")] public GameObject errorPatchHighPrefab;
        [Tooltip("Warning sign, medium error.")] public GameObject errorPatchMediumPrefab;
        public Material errorHigh;
        public Material errorMedium;
        [Tooltip("Low error; empty keeps the prefab's own material.")] public Material errorLow;

        [Header("UI")]
        public Button startButton;
        public Button stopButton;
        [Tooltip("Optional: continues a failed upload where the server's copy ends.")] public Button retryButton;
        public Text status;
        public Text trajectoryDuration;
        public Text trajectoryLength;
        public Text trajectoryDepth;
        [Tooltip("Shows the selected sub-trajectory's camera thumbnail (ShowEvidence).")]
        public RawImage evidenceThumbnail;
        [Tooltip("Shows the selected sub-trajectory's likely causes (ShowEvidence).")]
        public Text evidenceCauses;
        public Text trajectoryRegions;
        [Tooltip("Shown when the results are too noisy to trust.")] public GameObject unreliableWarning;
        public VisualizationStyle style = VisualizationStyle.WarningSigns;

#if UNITY_ANDROID
        ARSession arSession;
#endif
        SitarSession session;
        UploadJob upload;
        // The server session of a failed upload: a retry continues it instead of starting over.
        string failedServerId;
        string mp4Path;
        bool recording;
        uint drawnRevision;
        readonly List<GameObject> spawned = new List<GameObject>();
        readonly List<GameObject> markerObjects = new List<GameObject>();
        long lastFrameNs;

        /// <summary>The current session (null before the first Start).</summary>
        public SitarSession Session { get { return session; } }
        /// <summary>Whether frames are being recorded (between Start and Stop).</summary>
        public bool IsRecording { get { return recording; } }
        /// <summary>The timestamp of the latest camera frame (ns), for anchor observations.</summary>
        public long LastFrameNs { get { return lastFrameNs; } }
        /// <summary>The marker objects drawn, in SitarSession.Markers() order (SitarVenue pulses them).</summary>
        public IReadOnlyList<GameObject> MarkerObjects { get { return markerObjects; } }

        void Awake()
        {
#if UNITY_ANDROID
            arSession = GetComponent<ARSession>();
#endif
            mp4Path = Path.Combine(Application.persistentDataPath, "arcore-session.mp4");
            if (startButton != null) startButton.onClick.AddListener(StartRecording);
            if (stopButton != null) stopButton.onClick.AddListener(StopRecording);
            if (retryButton != null) retryButton.onClick.AddListener(RetryUpload);
            SetStatus("Press Start to record");
        }

        void OnEnable()
        {
            if (cameraManager != null) cameraManager.frameReceived += OnCameraFrame;
        }

        void OnDisable()
        {
            if (cameraManager != null) cameraManager.frameReceived -= OnCameraFrame;
        }

        void OnDestroy()
        {
            if (upload != null) upload.Dispose();
            if (session != null) session.Dispose();
        }

        Pose CameraPose()
        {
            Vector3 p = arCamera.position;
            Quaternion q = arCamera.rotation;
            return new Pose(p.x, p.y, p.z, q.x, q.y, q.z, q.w);
        }

        public void StartRecording()
        {
            if (recording || startPending) return;
            Clear();
            if (upload != null) { upload.Dispose(); upload = null; }
            if (session != null) session.Dispose();
            session = new SitarSession(new SitarJson().Add("convention", "unity").Add("server_url", serverUrl).ToString());
            if (calibration != null)
            {
                try
                {
                    session.SetCalibration(calibration.text);
                }
                catch (SitarException e)
                {
                    // Recording goes on: the walk waits for the backend's colours instead.
                    Debug.LogError("SiTAR: the bundled calibration was refused: " + e.Message);
                }
            }
#if UNITY_ANDROID
            if (arSession.subsystem is ARCoreSessionSubsystem sub)
            {
                using (var config = new ArRecordingConfig(sub.session))
                {
                    config.SetMp4DatasetFilePath(sub.session, mp4Path);
                    ArStatus st = sub.StartRecording(config);
                    if (st != ArStatus.Success) Debug.LogWarning("SiTAR: the ARCore recording did not start: " + st);
                }
            }
#endif
            drawnRevision = 0;
            // Start and stop happen on the next camera frame, so all timestamps share its clock.
            startPending = true;
            SetStatus("Recording… walk, then press Stop");
        }

        bool startPending;
        bool stopPending;

        void OnCameraFrame(ARCameraFrameEventArgs args)
        {
            if (!args.timestampNs.HasValue) return;
            long t = args.timestampNs.Value;
            lastFrameNs = t;
            if (startPending)
            {
                startPending = false;
                session.Start(t, CameraPose());
                recording = true;
                return;
            }
            if (!recording) return;
            if (stopPending)
            {
                stopPending = false;
                FinishRecording(t);
                return;
            }
            try
            {
                uint flags = session.Frame(t, CameraPose());
                if ((flags & SitarSession.Midpoint) != 0)
                {
                    GiveImage();
                    GiveDepth();
                }
            }
            catch (SitarException e)
            {
                Debug.LogWarning("SiTAR frame: " + e.Message);
            }
        }

        /// <summary>Clockwise rotation from the (landscape) sensor image to the display.</summary>
        static int DisplayRotation()
        {
            switch (Screen.orientation)
            {
                case ScreenOrientation.Portrait: return 90;
                case ScreenOrientation.LandscapeRight: return 180;
                case ScreenOrientation.PortraitUpsideDown: return 270;
                default: return 0;
            }
        }

        /// <summary>The camera image's Y plane at a midpoint: its thumbnail and properties are the
        /// evidence shown next to a marker (the paper's backup view).</summary>
        unsafe void GiveImage()
        {
            if (cameraManager == null || !cameraManager.TryAcquireLatestCpuImage(out XRCpuImage image)) return;
            using (image)
            {
                XRCpuImage.Plane plane = image.GetPlane(0);
                var data = (IntPtr)NativeArrayUnsafeUtility.GetUnsafeReadOnlyPtr(plane.data);
                try
                {
                    session.Image(data, image.width, image.height, plane.rowStride, DisplayRotation());
                }
                catch (SitarException e)
                {
                    Debug.Log("SiTAR camera image skipped: " + e.Message);
                }
            }
        }

        /// <summary>
        /// Shows what the camera saw at sub-trajectory k (e.g. the selected marker's
        /// Subtrajectory): its thumbnail in <see cref="evidenceThumbnail"/> and its likely causes
        /// in <see cref="evidenceCauses"/>.
        /// </summary>
        public void ShowEvidence(uint k)
        {
            if (session == null) return;
            try
            {
                Evidence e = session.SubtrajectoryEvidence(k);
                if (evidenceCauses != null)
                {
                    evidenceCauses.text = e.Causes == Causes.None ? "no likely cause seen" : e.Causes.ToString();
                }
                byte[] jpeg = session.Thumbnail(k);
                if (evidenceThumbnail != null && jpeg.Length > 0)
                {
                    var texture = new Texture2D(2, 2);
                    texture.LoadImage(jpeg);
                    evidenceThumbnail.texture = texture;
                }
            }
            catch (SitarException e)
            {
                Debug.LogWarning("SiTAR evidence: " + e.Message);
            }
        }

        unsafe void GiveDepth()
        {
            if (occlusionManager == null || !occlusionManager.TryAcquireEnvironmentDepthCpuImage(out XRCpuImage image)) return;
            using (image)
            {
                if (!cameraManager.TryGetIntrinsics(out XRCameraIntrinsics ci)) return;
                // Camera intrinsics are for the camera image; scale them to the depth image.
                double sx = (double)image.width / ci.resolution.x;
                double sy = (double)image.height / ci.resolution.y;
                var k = new Intrinsics(ci.focalLength.x * sx, ci.focalLength.y * sy, ci.principalPoint.x * sx, ci.principalPoint.y * sy);
                XRCpuImage.Plane plane = image.GetPlane(0);
                var data = (IntPtr)NativeArrayUnsafeUtility.GetUnsafeReadOnlyPtr(plane.data);
                try
                {
                    session.Depth(data, image.width, image.height, plane.rowStride, k, DisplayRotation());
                }
                catch (SitarException e)
                {
                    Debug.Log("SiTAR depth sample skipped: " + e.Message);
                }
            }
        }

        public void StopRecording()
        {
            if (recording) stopPending = true;
        }

        void FinishRecording(long t)
        {
            recording = false;
#if UNITY_ANDROID
            if (arSession.subsystem is ARCoreSessionSubsystem sub)
            {
                ArStatus st = sub.StopRecording();
                if (st != ArStatus.Success) Debug.LogWarning("SiTAR: the ARCore recording did not stop cleanly: " + st);
            }
#endif
            Summary s = session.Stop(t, CameraPose());
            if (trajectoryDuration != null) trajectoryDuration.text = s.DurationS.ToString("F1") + " s";
            if (trajectoryLength != null) trajectoryLength.text = s.LengthM.ToString("F2") + " m";
            if (trajectoryDepth != null) trajectoryDepth.text = s.MeanDepthM.ToString("F2") + " m";
            session.Save(Path.Combine(Application.persistentDataPath, "sitar-session"));
            Draw();
            failedServerId = null;
            StartUpload(null);
        }

        /// <summary>The upload options; <paramref name="serverSessionId"/> (or null) continues that server session.</summary>
        string UploadOptions(string serverSessionId)
        {
            var options = new SitarJson().Add("trials", trials).Add("setting", setting).Add("playback", playback);
            if (!string.IsNullOrEmpty(serverToken)) options.Add("server_token", serverToken);
            if (!string.IsNullOrEmpty(serverCertSha256)) options.Add("server_cert_sha256", serverCertSha256);
            if (!string.IsNullOrEmpty(serverSessionId)) options.Add("session_id", serverSessionId);
            return options.ToString();
        }

        void StartUpload(string serverSessionId)
        {
            // Android: unpinned https trusts the device's trust store (once per process).
            SitarPlatformTls.Init();
            upload = session.Upload(mp4Path, UploadOptions(serverSessionId));
            SetStatus("Uploading…");
        }

        /// <summary>After a failed upload (e.g. the Wi-Fi dropped): continues the same server
        /// session; the recording upload resumes from the bytes the server kept.</summary>
        public void RetryUpload()
        {
            if (upload != null || string.IsNullOrEmpty(failedServerId)) return;
            StartUpload(failedServerId);
        }

        void Update()
        {
            if (upload == null) return;
            UploadProgress p = upload.Progress();
            if (p.ResultsRevision != drawnRevision)
            {
                drawnRevision = p.ResultsRevision;
                Draw();
            }
            switch (p.State)
            {
                case UploadState.Failed:
                    failedServerId = upload.ServerId();
                    SetStatus("Failed: " + upload.Message() + (string.IsNullOrEmpty(failedServerId) ? "" : " (Retry continues it)"));
                    upload.Dispose();
                    upload = null;
                    break;
                case UploadState.Done:
                    SetStatus("Results ready");
                    upload.Dispose();
                    upload = null;
                    break;
                case UploadState.Cancelled:
                    upload.Dispose();
                    upload = null;
                    break;
                default:
                    string eta = p.EtaS >= 0 ? ", about " + Mathf.CeilToInt((float)p.EtaS) + " s left" : "";
                    SetStatus(p.State + " " + Mathf.RoundToInt((float)(p.Progress * 100)) + " % (" + p.TrialsDone + "/" + p.TrialsTotal + " trials" + eta + ")");
                    break;
            }
        }

        public void CancelUpload()
        {
            if (upload != null) upload.Cancel();
        }

        void SetStatus(string text)
        {
            if (status != null) status.text = text;
        }

        void Clear()
        {
            foreach (GameObject g in spawned) Destroy(g);
            spawned.Clear();
            markerObjects.Clear();
            if (unreliableWarning != null) unreliableWarning.SetActive(false);
            if (resultsSource != null) resultsSource.text = "";
        }

        static Vector3 V(double x, double y, double z)
        {
            return new Vector3((float)x, (float)y, (float)z);
        }

        static Quaternion Q(double x, double y, double z, double w)
        {
            return new Quaternion((float)x, (float)y, (float)z, (float)w);
        }

        Material MaterialFor(ErrorClass c)
        {
            switch (c)
            {
                case ErrorClass.High: return errorHigh;
                case ErrorClass.Medium: return errorMedium;
                case ErrorClass.Low: return errorLow;
                default: return null;
            }
        }

        GameObject Spawn(GameObject prefab, Vector3 position, Quaternion rotation, ErrorClass c)
        {
            if (prefab == null) return null;
            GameObject g = Instantiate(prefab, position, rotation);
            Material m = MaterialFor(c);
            if (m != null)
            {
                foreach (Renderer r in g.GetComponentsInChildren<Renderer>()) r.sharedMaterial = m;
            }
            spawned.Add(g);
            return g;
        }

        /// <summary>Draws the render plan (and markers, if results are loaded) in the chosen style.</summary>
        public void Draw()
        {
            if (session == null) return;
            Clear();
            RenderPlan plan = session.GetRenderPlan();
            foreach (Segment s in plan.Segments)
            {
                GameObject g = Spawn(cylinderPrefab, V(s.Cx, s.Cy, s.Cz), Q(s.Qx, s.Qy, s.Qz, s.Qw), s.ErrorClass);
                // Unity's cylinder is 2 units tall along its local +Y.
                if (g != null) g.transform.localScale = new Vector3(g.transform.localScale.x, (float)s.Length / 2, g.transform.localScale.z);
            }
            foreach (Joint j in plan.Joints) Spawn(jointPrefab, V(j.Px, j.Py, j.Pz), Quaternion.identity, j.ErrorClass);
            foreach (Frustum f in plan.Frustums) Spawn(frustumPrefab, V(f.Pose.Px, f.Pose.Py, f.Pose.Pz), Q(f.Pose.Qx, f.Pose.Qy, f.Pose.Qz, f.Pose.Qw), f.ErrorClass);
            if (plan.Start.HasValue) Spawn(startPrefab, V(plan.Start.Value.Px, plan.Start.Value.Py, plan.Start.Value.Pz), Quaternion.identity, ErrorClass.Unknown);
            if (plan.Stop.HasValue) Spawn(stopPrefab, V(plan.Stop.Value.Px, plan.Stop.Value.Py, plan.Stop.Value.Pz), Quaternion.identity, ErrorClass.Unknown);

            Marker[] markers;
            try
            {
                markers = session.Markers();
            }
            catch (SitarException)
            {
                return; // no results yet
            }
            if (trajectoryRegions != null) trajectoryRegions.text = markers.Length.ToString();
            if (unreliableWarning != null) unreliableWarning.SetActive(session.ResultsUnreliable());
            if (resultsSource != null) resultsSource.text = Describe(session.ResultsProvenance());
            if (style == VisualizationStyle.TrajectoryOnly) return;
            foreach (Marker m in markers)
            {
                bool high = m.ErrorClass == ErrorClass.High;
                GameObject g;
                if (style == VisualizationStyle.ExclamationPoints)
                {
                    g = Spawn(high ? errorAreaHighPrefab : errorAreaMediumPrefab, V(m.Px, m.Py, m.Pz), Quaternion.identity, ErrorClass.Unknown);
                }
                else
                {
                    g = Spawn(high ? errorPatchHighPrefab : errorPatchMediumPrefab, V(m.Px, m.Py, m.Pz), Q(m.Qx, m.Qy, m.Qz, m.Qw), ErrorClass.Unknown);
                }
                markerObjects.Add(g); // null without a prefab: the index still follows Markers()
            }
        }

        /// <summary>Where the colours come from, for <see cref="resultsSource"/>.</summary>
        static string Describe(Provenance p)
        {
            string from;
            switch (p.Source)
            {
                case ResultSource.Walk: from = "From your walk"; break;
                case ResultSource.Replays: from = p.Runs.HasValue ? "From replays (" + p.Runs.Value + " runs)" : "From replays"; break;
                default: from = "From the server"; break;
            }
            return p.IsGuess ? from + ". This system's error cannot be told from its runs: colours are a guess." : from;
        }

        /// <summary>Switches style (e.g. from a UI dropdown) and redraws.</summary>
        public void SetStyle(int newStyle)
        {
            style = (VisualizationStyle)newStyle;
            Draw();
        }
    }
}
