// The playback-device MonoBehaviour (replaces the original TrajectoryPlayback.cs):
// replays the recorded mp4 through ARCore, logs the camera pose every frame
// through libsitar and writes trajectory_{first+k}.txt (TUM, integer
// nanoseconds) after trial k, with a one-line status.txt beside them: the adb
// contract of docs/playback-contract.md. `sitar serve --playback adb
// --adb-package <bundle id> --adb-activity com.unity3d.player.UnityPlayerActivity`
// starts the app with the intent extras `trials`, `first` (ints), `recording`
// and `output` (paths); they are read on every launch (a new intent reaches a
// running app too), not only in Awake. Without extras: Num Playbacks trials of
// persistentDataPath/recording.mp4 into persistentDataPath/out. The logic is
// SitarPlaybackRun (no UnityEngine); this class connects it to AR Foundation.
using System;
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
        /// <summary>The adb contract's names (docs/playback-contract.md), as the backend sends them.</summary>
        public const string ExtraTrials = PlaybackRequest.ExtraTrials;
        public const string ExtraFirst = PlaybackRequest.ExtraFirst;
        public const string ExtraRecording = PlaybackRequest.ExtraRecording;
        public const string ExtraOutput = PlaybackRequest.ExtraOutput;
        public const string RecordingFile = PlaybackRequest.RecordingFile;
        public const string OutputDir = PlaybackRequest.OutputDir;
        public const string StatusFile = PlaybackRequest.StatusFile;

        [SerializeField] ARCameraManager cameraManager;
        public Transform arCamera;
        public Text log;
        [Tooltip("Trials of a launch without extras (the backend's launches say how many).")]
        public int numPlaybacks = 5;
        [Tooltip("Camera frames to wait before a playback starts (the AR session must be running).")]
        public int warmupFrames = 60;

        readonly SitarPlaybackRun run = new SitarPlaybackRun(() => new LibraryTrialLog());
        // The intent last read: another one is a new launch.
        int intentId;
#if UNITY_ANDROID
        ARSession arSession;
        // The Play step waiting for the AR session to run, and the frames left to wait.
        PlaybackStep pending;
        int framesUntilPlay;
#endif
#if UNITY_ANDROID && !UNITY_EDITOR
        static readonly bool OnPhone = true;
#else
        static readonly bool OnPhone = false;
#endif

        void Awake()
        {
            // A playback phone lies on a desk for hours: a dimmed screen must not pause ARCore.
            Screen.sleepTimeout = SleepTimeout.NeverSleep;
#if UNITY_ANDROID
            arSession = GetComponent<ARSession>();
#endif
            if (OnPhone) ReadLaunch();
            else Say("Playback needs ARCore on an Android phone");
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
            run.Dispose();
        }

        void Start()
        {
            if (OnPhone) Perform(run.OnResume());
        }

        void OnApplicationPause(bool paused)
        {
            if (!OnPhone) return;
            if (paused)
            {
                run.OnPause();
#if UNITY_ANDROID
                pending = null;
#endif
                Say(run.Line);
                return;
            }
            // Resumed: a new intent (UnityPlayerActivity.onNewIntent sets it) is a new launch.
            ReadLaunch();
            Perform(run.OnResume());
        }

        void OnApplicationFocus(bool focused)
        {
            if (OnPhone && focused) ReadLaunch();
        }

        /// <summary>Reads the launch intent's extras if the intent is new.</summary>
        void ReadLaunch()
        {
            string files = Application.persistentDataPath;
            Func<string, int, int> intExtra = (name, fallback) => fallback;
            Func<string, string> stringExtra = name => null;
            int id = 1;
#if UNITY_ANDROID && !UNITY_EDITOR
            AndroidJavaObject intent;
            using (var player = new AndroidJavaClass("com.unity3d.player.UnityPlayer"))
            using (var activity = player.GetStatic<AndroidJavaObject>("currentActivity"))
            {
                intent = activity.Call<AndroidJavaObject>("getIntent");
            }
            if (intent == null) return;
            using (intent)
            {
                // Intent keeps Object.hashCode: a new intent has (almost surely) another one.
                id = intent.Call<int>("hashCode");
                if (id == intentId) return;
                int trials = intent.Call<int>("getIntExtra", ExtraTrials, numPlaybacks);
                int first = intent.Call<int>("getIntExtra", ExtraFirst, 0);
                string recording = intent.Call<string>("getStringExtra", ExtraRecording);
                string output = intent.Call<string>("getStringExtra", ExtraOutput);
                intExtra = (name, fallback) => name == ExtraTrials ? trials : name == ExtraFirst ? first : fallback;
                stringExtra = name => name == ExtraRecording ? recording : name == ExtraOutput ? output : null;
            }
#else
            if (id == intentId) return;
#endif
            intentId = id;
            PlaybackStep step;
            try
            {
                step = run.Launch(PlaybackRequest.From(intExtra, stringExtra, files, numPlaybacks));
            }
            catch (ArgumentException e)
            {
                step = run.Refuse(stringExtra(ExtraOutput) ?? Path.Combine(files, OutputDir), e.Message);
            }
            Perform(step);
        }

        void Perform(PlaybackStep step)
        {
            switch (step.Kind)
            {
                case PlaybackStep.Kinds.Play:
#if UNITY_ANDROID
                    // Start on a later camera frame: the AR session must be running.
                    pending = step;
                    framesUntilPlay = step.Trial == 0 ? warmupFrames : 1;
#endif
                    Say("Trial " + (step.Trial + 1) + "/" + step.Of + " starts shortly");
                    break;
                case PlaybackStep.Kinds.Done:
                    Say("Playback finished: " + step.Of + " trials written");
                    break;
                case PlaybackStep.Kinds.Failed:
                    Debug.LogWarning("SiTAR playback: " + step.Message);
                    Say("Failed: " + step.Message);
                    break;
                default:
                    Say(run.Line);
                    break;
            }
        }

        void Say(string text)
        {
            if (log != null) log.text = text;
        }

        void OnCameraFrame(ARCameraFrameEventArgs args)
        {
#if UNITY_ANDROID
            if (!(arSession.subsystem is ARCoreSessionSubsystem sub) || !args.timestampNs.HasValue) return;
            if (pending != null)
            {
                if (--framesUntilPlay > 0) return;
                PlaybackStep play = pending;
                pending = null;
                if (!run.IsCurrent(play.Token)) return;
                ArStatus st = sub.StartPlayback(play.Recording);
                if (st != ArStatus.Success)
                {
                    Perform(run.Fail("ARCore cannot play " + play.Recording + ": " + st));
                    return;
                }
                run.Started(play.Token);
                Say("Trial " + (play.Trial + 1) + "/" + play.Of + " playing");
                return;
            }
            Vector3 p = arCamera.position;
            Quaternion q = arCamera.rotation;
            PlaybackStep next = run.OnFrame(args.timestampNs.Value, new Pose(p.x, p.y, p.z, q.x, q.y, q.z, q.w), Progress(sub.playbackStatus));
            if (next.Kind != PlaybackStep.Kinds.Wait) Perform(next);
#endif
        }

#if UNITY_ANDROID
        static PlaybackProgress Progress(ArPlaybackStatus status)
        {
            switch (status)
            {
                case ArPlaybackStatus.Ok: return PlaybackProgress.Ok;
                case ArPlaybackStatus.IOError: return PlaybackProgress.IoError;
                case ArPlaybackStatus.Finished: return PlaybackProgress.Finished;
                default: return PlaybackProgress.None;
            }
        }
#endif
    }
}
