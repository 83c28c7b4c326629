// The playback device's logic, free of UnityEngine (the host test runs it on
// Mono): launches, the app's pause and resume, every camera frame, the
// trajectory and status files of the adb contract (docs/playback-contract.md).
// SitarPlaybackLogger (the MonoBehaviour) drives it; the Kotlin playback app
// has the same logic (android/playback/.../PlaybackRun.kt).
using System;
using System.IO;

namespace Sitar
{
    /// <summary>What one launch asks for: the backend's <c>am start</c> extras.</summary>
    public sealed class PlaybackRequest
    {
        /// <summary>Int extra: how many trials to play.</summary>
        public const string ExtraTrials = "trials";
        /// <summary>Int extra: the number of the first trial's file.</summary>
        public const string ExtraFirst = "first";
        /// <summary>String extra: the recording (mp4) to replay.</summary>
        public const string ExtraRecording = "recording";
        /// <summary>String extra: the folder for the trajectories and the status file.</summary>
        public const string ExtraOutput = "output";
        /// <summary>The recording's name in the app's folder (the backend's push target).</summary>
        public const string RecordingFile = "recording.mp4";
        /// <summary>The output folder's name in the app's folder.</summary>
        public const string OutputDir = "out";
        /// <summary>The one-line status file in the output folder.</summary>
        public const string StatusFile = "status.txt";
        /// <summary>More trials than this in one launch is a mistake, not a plan.</summary>
        public const int MaxTrials = 1000;

        public int Trials { get; private set; }
        public int First { get; private set; }
        public string Recording { get; private set; }
        public string Output { get; private set; }

        /// <summary>
        /// The request of a launch: <paramref name="intExtra"/>(name, default) and
        /// <paramref name="stringExtra"/>(name) read the intent (null when absent).
        /// Missing extras take the defaults of a launch by hand: <paramref name="defaultTrials"/>
        /// from 0, <c>FILES/recording.mp4</c> into <c>FILES/out</c> (<paramref name="filesDir"/>
        /// is the app's own folder, Unity's persistentDataPath). A value that cannot be right
        /// throws ArgumentException naming the extra.
        /// </summary>
        public static PlaybackRequest From(Func<string, int, int> intExtra, Func<string, string> stringExtra, string filesDir, int defaultTrials)
        {
            int trials = intExtra(ExtraTrials, defaultTrials);
            if (trials < 1 || trials > MaxTrials) throw new ArgumentException("extra " + ExtraTrials + " = " + trials + ": expected 1 … " + MaxTrials);
            int first = intExtra(ExtraFirst, 0);
            if (first < 0) throw new ArgumentException("extra " + ExtraFirst + " = " + first + ": expected 0 or more");
            string recording = stringExtra(ExtraRecording) ?? Path.Combine(filesDir, RecordingFile);
            if (recording.Trim().Length == 0) throw new ArgumentException("extra " + ExtraRecording + " is empty");
            string output = stringExtra(ExtraOutput) ?? Path.Combine(filesDir, OutputDir);
            if (output.Trim().Length == 0) throw new ArgumentException("extra " + ExtraOutput + " is empty");
            return new PlaybackRequest { Trials = trials, First = first, Recording = recording, Output = output };
        }
    }

    /// <summary>ARCore's playback status, without ARCore.</summary>
    public enum PlaybackProgress { None, Ok, IoError, Finished }

    /// <summary>One trial's pose log: <see cref="PlaybackLogger"/> in the app.</summary>
    public interface ITrialLog : IDisposable
    {
        void Log(long tNs, Pose pose);
        ulong Count { get; }
        /// <summary>Writes dir/trajectory_index.txt whole (temp name, then rename).</summary>
        void Write(string dir, uint index);
    }

    /// <summary>A trial's log in libsitar (poses in Unity's convention).</summary>
    public sealed class LibraryTrialLog : ITrialLog
    {
        private readonly PlaybackLogger logger = new PlaybackLogger(new SitarJson().Add("convention", "unity").ToString());

        public void Log(long tNs, Pose pose) { logger.Log(tNs, pose); }
        public ulong Count { get { return logger.Count; } }
        public void Write(string dir, uint index) { logger.Write(dir, index); }
        public void Dispose() { logger.Dispose(); }
    }

    /// <summary>What the app does next.</summary>
    public sealed class PlaybackStep
    {
        public enum Kinds { Wait, Play, Done, Failed }

        public Kinds Kind { get; private set; }
        /// <summary>Play: the dataset to start (then call <see cref="SitarPlaybackRun.Started"/> with Token).</summary>
        public string Recording { get; private set; }
        public int Trial { get; private set; }
        public int Of { get; private set; }
        public long Token { get; private set; }
        /// <summary>Failed: why (also in the status file).</summary>
        public string Message { get; private set; }

        public static readonly PlaybackStep Wait = new PlaybackStep { Kind = Kinds.Wait };

        internal static PlaybackStep Play(string recording, int trial, int of, long token)
        {
            return new PlaybackStep { Kind = Kinds.Play, Recording = recording, Trial = trial, Of = of, Token = token };
        }

        internal static PlaybackStep Done(int trials) { return new PlaybackStep { Kind = Kinds.Done, Of = trials }; }

        internal static PlaybackStep Failed(string message) { return new PlaybackStep { Kind = Kinds.Failed, Message = message }; }

        public override string ToString()
        {
            return Kind + (Kind == Kinds.Play ? " " + (Trial + 1) + "/" + Of : "") + (Message != null ? ": " + Message : "");
        }
    }

    /// <summary>
    /// The one-line status the backend reads (<c>status.txt</c>): <c>starting</c>,
    /// <c>playing K/N</c>, <c>paused K/N</c>, <c>done N/N</c> or <c>failed MESSAGE</c>.
    /// Every write is whole: a temp name beside it, then a rename over it.
    /// </summary>
    public sealed class PlaybackStatusFile
    {
        public string FilePath { get; private set; }
        public string Line { get; private set; }

        public PlaybackStatusFile(string path) { FilePath = path; Line = ""; }

        public void Starting() { Write("starting"); }
        public void Playing(int trial, int of) { Write("playing " + (trial + 1) + "/" + of); }
        public void Paused(int trial, int of) { Write("paused " + (trial + 1) + "/" + of); }
        public void Done(int of) { Write("done " + of + "/" + of); }
        public void Failed(string message) { Write("failed " + message.Replace('\n', ' ').Replace('\r', ' ').Trim()); }

        private void Write(string text)
        {
            Line = text;
            WriteAtomically(FilePath, text + "\n");
        }

        /// <summary>Writes text to path whole or not at all (rename is atomic on Android's file systems).</summary>
        public static void WriteAtomically(string path, string text)
        {
            string dir = Path.GetDirectoryName(Path.GetFullPath(path));
            Directory.CreateDirectory(dir);
            string partial = Path.Combine(dir, "." + Path.GetFileName(path) + ".part");
            File.WriteAllText(partial, text);
            if (File.Exists(path)) File.Replace(partial, path, null);
            else File.Move(partial, path);
        }
    }

    /// <summary>
    /// The playback logic: a launch (first start or a new intent) replaces whatever
    /// ran; a pause drops the unfinished trial (ARCore does not replay the frames it
    /// skipped while paused), which restarts on resume; each finished trial k is
    /// written as <c>trajectory_{first + k}.txt</c> at once. Thread-safe.
    /// </summary>
    public sealed class SitarPlaybackRun : IDisposable
    {
        private readonly Func<ITrialLog> newLog;
        private readonly object gate = new object();
        private PlaybackRequest request;
        private PlaybackStatusFile status;
        private int trial;
        private ITrialLog log;
        private long lastT = long.MinValue;
        private bool resumed;
        private long token;

        public SitarPlaybackRun(Func<ITrialLog> newLog) { this.newLog = newLog; }

        /// <summary>What the screen shows.</summary>
        public string Line { get { lock (gate) return status != null ? status.Line : "waiting for a launch"; } }

        /// <summary>A launch of the app with <paramref name="next"/>.</summary>
        public PlaybackStep Launch(PlaybackRequest next)
        {
            lock (gate)
            {
                // An unfinished run elsewhere says why it stops; in the same folder the new status replaces it.
                if (request != null && Path.GetFullPath(request.Output) != Path.GetFullPath(next.Output))
                {
                    Report(s => s.Failed("superseded by a new launch"));
                }
                DropTrial();
                request = next;
                trial = 0;
                status = new PlaybackStatusFile(Path.Combine(next.Output, PlaybackRequest.StatusFile));
                try
                {
                    Directory.CreateDirectory(next.Output);
                }
                catch (Exception e)
                {
                    return End("cannot create the output folder " + next.Output + ": " + e.Message);
                }
                if (!CanRead(next.Recording)) return End("cannot read the recording " + next.Recording);
                Report(s => s.Starting());
                return resumed ? Begin() : PlaybackStep.Wait;
            }
        }

        /// <summary>A launch whose extras were refused: reported in <paramref name="output"/>'s status file.</summary>
        public PlaybackStep Refuse(string output, string message)
        {
            lock (gate)
            {
                DropTrial();
                request = null;
                status = new PlaybackStatusFile(Path.Combine(output, PlaybackRequest.StatusFile));
                return End(message);
            }
        }

        /// <summary>The app resumed: the unfinished trial (if any) starts (again).</summary>
        public PlaybackStep OnResume()
        {
            lock (gate)
            {
                resumed = true;
                return request != null ? Begin() : PlaybackStep.Wait;
            }
        }

        /// <summary>The app paused: the unfinished trial is dropped.</summary>
        public void OnPause()
        {
            lock (gate)
            {
                resumed = false;
                if (request == null) return;
                DropTrial();
                int t = trial, n = request.Trials;
                Report(s => s.Paused(t, n));
            }
        }

        /// <summary>ARCore plays the dataset of the Play step with <paramref name="playToken"/>.</summary>
        public void Started(long playToken)
        {
            lock (gate)
            {
                if (playToken != token || request == null) return;
                lastT = long.MinValue;
                if (log != null) log.Dispose();
                log = newLog();
            }
        }

        /// <summary>Whether <paramref name="playToken"/> is the latest Play step of a resumed, running launch.</summary>
        public bool IsCurrent(long playToken)
        {
            lock (gate) return playToken == token && resumed && request != null;
        }

        /// <summary>One camera frame: timestamp, pose, ARCore's playback status.</summary>
        public PlaybackStep OnFrame(long tNs, Pose pose, PlaybackProgress progress)
        {
            lock (gate)
            {
                if (request == null || log == null) return PlaybackStep.Wait;
                switch (progress)
                {
                    case PlaybackProgress.Ok:
                        // ARCore hands out the same frame again when no new camera image arrived.
                        if (tNs > lastT)
                        {
                            log.Log(tNs, pose);
                            lastT = tNs;
                        }
                        return PlaybackStep.Wait;
                    case PlaybackProgress.IoError:
                        return End("ARCore stopped playing " + request.Recording + " with IO_ERROR in trial " + (trial + 1) + "/" + request.Trials);
                    case PlaybackProgress.Finished:
                        return FinishTrial();
                    default:
                        return PlaybackStep.Wait;
                }
            }
        }

        /// <summary>ARCore or the app failed: the run ends with <paramref name="message"/>.</summary>
        public PlaybackStep Fail(string message)
        {
            lock (gate) return End(message);
        }

        public void Dispose()
        {
            lock (gate) DropTrial();
        }

        private PlaybackStep FinishTrial()
        {
            PlaybackRequest r = request;
            if (log.Count == 0) return End("ARCore played " + r.Recording + " but gave no frame in trial " + (trial + 1) + "/" + r.Trials);
            try
            {
                log.Write(r.Output, (uint)(r.First + trial));
            }
            catch (SitarException e)
            {
                return End("cannot write trajectory_" + (r.First + trial) + ".txt into " + r.Output + ": " + e.Message);
            }
            DropTrial();
            trial++;
            if (trial < r.Trials) return Begin();
            Report(s => s.Done(r.Trials));
            request = null;
            return PlaybackStep.Done(r.Trials);
        }

        private PlaybackStep Begin()
        {
            DropTrial();
            token++;
            int t = trial, n = request.Trials;
            Report(s => s.Playing(t, n));
            return PlaybackStep.Play(request.Recording, trial, request.Trials, token);
        }

        private void DropTrial()
        {
            if (log != null) log.Dispose();
            log = null;
        }

        private PlaybackStep End(string message)
        {
            DropTrial();
            request = null;
            Report(s => s.Failed(message));
            return PlaybackStep.Failed(message);
        }

        private void Report(Action<PlaybackStatusFile> write)
        {
            if (status == null) return;
            try
            {
                write(status);
            }
            catch (IOException)
            {
                // Nothing else to tell: the status file is how the backend hears of problems.
            }
            catch (UnauthorizedAccessException)
            {
            }
        }

        private static bool CanRead(string path)
        {
            try
            {
                using (File.OpenRead(path)) return true;
            }
            catch (Exception)
            {
                return false;
            }
        }
    }
}
