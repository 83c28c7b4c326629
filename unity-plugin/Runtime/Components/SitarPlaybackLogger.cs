// The playback-device MonoBehaviour (replaces the original TrajectoryPlayback.cs):
// replays the recorded mp4 through ARCore numPlaybacks times, logs the camera
// pose every frame through libsitar, and writes trajectory_K.txt (K = 0 … N−1;
// TUM, integer nanoseconds) after each playback. `sitar serve --playback adb`
// starts the app with the intent extras `trials` (int), `recording` and
// `output` (paths); without them the inspector values and
// Application.persistentDataPath are used.
using System.IO;
using UnityEngine;
using UnityEngine.UI;
using UnityEngine.XR.ARFoundation;
#if UNITY_ANDROID
using UnityEngine.XR.ARCore;
#endif

namespace Sitar.Unity
{
    [RequireComponent(typeof(ARSession))]
    public sealed class SitarPlaybackLogger : MonoBehaviour
    {
        [SerializeField] ARCameraManager cameraManager;
        public Transform arCamera;
        public Text log;
        public int numPlaybacks = 5;
        [Tooltip("Camera frames to wait before the first playback (the AR session must be running).")]
        public int warmupFrames = 60;

        PlaybackLogger logger;
#if UNITY_ANDROID
        ARSession arSession;
        string mp4Path;
        string outputDir;
        int frameCounter;
        int playbackCount;
        bool wasPlaying;
#endif

        void Awake()
        {
#if UNITY_ANDROID
            arSession = GetComponent<ARSession>();
            mp4Path = Path.Combine(Application.persistentDataPath, "arcore-session.mp4");
            outputDir = Application.persistentDataPath;
            ReadLaunchExtras();
#else
            Say("Playback needs ARCore (Android)");
#endif
        }

        // The backend's `am start … --ei trials N --es recording FILE --es output DIR`.
        void ReadLaunchExtras()
        {
#if UNITY_ANDROID && !UNITY_EDITOR
            using (var player = new AndroidJavaClass("com.unity3d.player.UnityPlayer"))
            using (var activity = player.GetStatic<AndroidJavaObject>("currentActivity"))
            using (var intent = activity.Call<AndroidJavaObject>("getIntent"))
            {
                if (intent == null) return;
                numPlaybacks = intent.Call<int>("getIntExtra", "trials", numPlaybacks);
                string recording = intent.Call<string>("getStringExtra", "recording");
                if (!string.IsNullOrEmpty(recording)) mp4Path = recording;
                string output = intent.Call<string>("getStringExtra", "output");
                if (!string.IsNullOrEmpty(output)) outputDir = output;
            }
#endif
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
            if (logger != null) logger.Dispose();
        }

        void Say(string text)
        {
            if (log != null) log.text = text;
        }

        void OnCameraFrame(ARCameraFrameEventArgs args)
        {
#if UNITY_ANDROID
            if (!(arSession.subsystem is ARCoreSessionSubsystem sub) || !args.timestampNs.HasValue) return;
            frameCounter++;
            if (frameCounter == warmupFrames)
            {
                if (!File.Exists(mp4Path))
                {
                    Say("No sequence found");
                    return;
                }
                BeginPlayback(sub);
            }
            bool playing = sub.playbackStatus.Playing();
            if (playing && logger != null)
            {
                Vector3 p = arCamera.position;
                Quaternion q = arCamera.rotation;
                logger.Log(args.timestampNs.Value, new Pose(p.x, p.y, p.z, q.x, q.y, q.z, q.w));
            }
            if (wasPlaying && sub.playbackStatus == ArPlaybackStatus.Finished)
            {
                logger.Write(outputDir, (uint)playbackCount);
                playbackCount++;
                logger.Dispose();
                logger = null;
                if (playbackCount < numPlaybacks)
                {
                    BeginPlayback(sub);
                }
                else
                {
                    playbackCount = 0;
                    Say("Playback finished");
                }
            }
            wasPlaying = playing;
#endif
        }

#if UNITY_ANDROID
        void BeginPlayback(ARCoreSessionSubsystem sub)
        {
            logger = new PlaybackLogger("{\"convention\":\"unity\"}");
            ArStatus st = sub.StartPlayback(mp4Path);
            Say(st == ArStatus.Success
                ? "Playback " + (playbackCount + 1) + " started"
                : "Playback " + (playbackCount + 1) + " did not start: " + st);
        }
#endif
    }
}
