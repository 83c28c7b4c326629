// Host test of the Unity package's UnityEngine-free logic on Mono, against the
// host-built libsitar (run by tests/tests/unity_logic.rs): SitarPlaybackRun
// (launches, pause/resume, a second launch, failures, the trajectory and
// status files) with the real PlaybackLogger, and SitarJson, whose documents
// are printed as "JSON <hex of the input> <document>" for serde_json.
// Args: <temp dir>. Prints "PASSED n checks".
using System;
using System.Collections.Generic;
using System.IO;
using System.Linq;
using System.Text;
using Sitar;

static class LogicTest
{
    static int checks;

    static void Check(bool condition, string what)
    {
        checks++;
        if (!condition) throw new Exception("check failed: " + what);
    }

    const long FrameNs = 33333333;

    static Pose PoseAt(int i)
    {
        return new Pose(0.01 * i, 1.5, -0.02 * i, 0, 0, 0, 1);
    }

    static PlaybackRequest Request(string files, int trials, int first, string output)
    {
        var ints = new Dictionary<string, int> { { PlaybackRequest.ExtraTrials, trials }, { PlaybackRequest.ExtraFirst, first } };
        var strings = new Dictionary<string, string>
        {
            { PlaybackRequest.ExtraRecording, Path.Combine(files, PlaybackRequest.RecordingFile) },
            { PlaybackRequest.ExtraOutput, Path.Combine(files, output) },
        };
        return PlaybackRequest.From((n, d) => ints.ContainsKey(n) ? ints[n] : d, n => strings.ContainsKey(n) ? strings[n] : null, files, 5);
    }

    static string Status(string dir)
    {
        return File.ReadAllText(Path.Combine(dir, PlaybackRequest.StatusFile));
    }

    static PlaybackStep PlayTrial(SitarPlaybackRun run, PlaybackStep step, int frames)
    {
        Check(step.Kind == PlaybackStep.Kinds.Play, "a Play step, got " + step);
        run.Started(step.Token);
        for (int i = 0; i < frames; i++)
        {
            Check(run.OnFrame(1000000000L + i * FrameNs, PoseAt(i), PlaybackProgress.Ok).Kind == PlaybackStep.Kinds.Wait, "frames ask for nothing");
        }
        return run.OnFrame(1000000000L + frames * FrameNs, PoseAt(frames), PlaybackProgress.Finished);
    }

    static int TumLines(string file)
    {
        Check(File.Exists(file), file + " exists");
        string[] lines = File.ReadAllLines(file).Where(l => l.Trim().Length > 0).ToArray();
        foreach (string l in lines)
        {
            string[] cols = l.Split(new[] { ' ', '\t' }, StringSplitOptions.RemoveEmptyEntries);
            long t;
            Check(cols.Length == 8 && long.TryParse(cols[0], out t), "TUM line with integer ns: " + l);
        }
        return lines.Length;
    }

    static void NoPartFiles(string dir)
    {
        Check(!Directory.GetFiles(dir).Any(f => f.EndsWith(".part")), "no half-written file in " + dir);
    }

    static string Fresh(string work, string name)
    {
        string files = Path.Combine(work, name);
        Directory.CreateDirectory(files);
        File.WriteAllText(Path.Combine(files, PlaybackRequest.RecordingFile), "mp4");
        return files;
    }

    static void EveryTrialIsWritten(string work)
    {
        string files = Fresh(work, "normal");
        using (var run = new SitarPlaybackRun(() => new LibraryTrialLog()))
        {
            PlaybackRequest r = Request(files, 3, 4, "out");
            Check(run.Launch(r).Kind == PlaybackStep.Kinds.Wait, "a launch before resume waits");
            Check(Status(r.Output) == "starting\n", "starting");
            PlaybackStep step = run.OnResume();
            Check(run.OnFrame(5, PoseAt(0), PlaybackProgress.Finished).Kind == PlaybackStep.Kinds.Wait, "no trial ends before it started");
            for (int k = 0; k < 3; k++) step = PlayTrial(run, step, 20 + k);
            Check(step.Kind == PlaybackStep.Kinds.Done && step.Of == 3, "done: " + step);
            Check(Status(r.Output) == "done 3/3\n", "done 3/3");
            for (int k = 0; k < 3; k++) Check(TumLines(Path.Combine(r.Output, "trajectory_" + (4 + k) + ".txt")) == 20 + k, "trial " + k);
            Check(!File.Exists(Path.Combine(r.Output, "trajectory_7.txt")), "only 4…6");
            NoPartFiles(r.Output);
        }
    }

    static void PauseDropsTheUnfinishedTrial(string work)
    {
        string files = Fresh(work, "pause");
        using (var run = new SitarPlaybackRun(() => new LibraryTrialLog()))
        {
            PlaybackRequest r = Request(files, 1, 0, "out");
            run.OnResume();
            PlaybackStep step = run.Launch(r);
            run.Started(step.Token);
            for (int i = 0; i < 10; i++) run.OnFrame(2000000000L + i * FrameNs, PoseAt(i), PlaybackProgress.Ok);
            run.OnPause();
            Check(Status(r.Output) == "paused 1/1\n", "paused: " + Status(r.Output));
            Check(!run.IsCurrent(step.Token), "the old step is stale");
            PlaybackStep again = run.OnResume();
            Check(again.Kind == PlaybackStep.Kinds.Play && again.Trial == 0 && again.Token != step.Token, "the trial starts again");
            PlaybackStep done = PlayTrial(run, again, 15);
            Check(done.Kind == PlaybackStep.Kinds.Done, "done");
            Check(TumLines(Path.Combine(r.Output, "trajectory_0.txt")) == 15, "only the replay after the resume");
        }
    }

    static void ASecondLaunchReplacesTheRunningOne(string work)
    {
        string files = Fresh(work, "second");
        using (var run = new SitarPlaybackRun(() => new LibraryTrialLog()))
        {
            run.OnResume();
            PlaybackRequest a = Request(files, 3, 0, "a");
            PlaybackStep step = PlayTrial(run, run.Launch(a), 8);
            long stale = step.Token;
            run.Started(stale);
            PlaybackRequest b = Request(files, 1, 7, "b");
            PlaybackStep playB = run.Launch(b);
            Check(playB.Kind == PlaybackStep.Kinds.Play && playB.Of == 1, "B plays at once");
            Check(Status(a.Output) == "failed superseded by a new launch\n", "A says why: " + Status(a.Output));
            run.Started(stale);
            Check(run.OnFrame(1, PoseAt(0), PlaybackProgress.Finished).Kind == PlaybackStep.Kinds.Wait, "B has not started");
            Check(PlayTrial(run, playB, 5).Kind == PlaybackStep.Kinds.Done, "B done");
            Check(TumLines(Path.Combine(b.Output, "trajectory_7.txt")) == 5, "B's trial is trajectory_7");
            Check(File.Exists(Path.Combine(a.Output, "trajectory_0.txt")) && !File.Exists(Path.Combine(a.Output, "trajectory_1.txt")), "A kept its finished trial");
        }
    }

    static void FailuresReachTheStatusFile(string work)
    {
        string files = Path.Combine(work, "fail");
        Directory.CreateDirectory(files);
        using (var run = new SitarPlaybackRun(() => new LibraryTrialLog()))
        {
            run.OnResume();
            PlaybackRequest r = Request(files, 2, 0, "out");
            PlaybackStep missing = run.Launch(r);
            Check(missing.Kind == PlaybackStep.Kinds.Failed && Status(r.Output).StartsWith("failed cannot read the recording " + r.Recording), Status(r.Output));
            File.WriteAllText(r.Recording, "mp4");
            PlaybackStep play = run.Launch(r);
            run.Started(play.Token);
            run.OnFrame(10, PoseAt(0), PlaybackProgress.Ok);
            Check(run.OnFrame(20, PoseAt(1), PlaybackProgress.IoError).Kind == PlaybackStep.Kinds.Failed, "IO_ERROR ends it");
            Check(Status(r.Output).StartsWith("failed ARCore stopped playing") && Status(r.Output).Contains("trial 1/2"), Status(r.Output));
            run.Launch(r);
            run.Fail("cannot play:\nERROR");
            Check(Status(r.Output) == "failed cannot play: ERROR\n", Status(r.Output));
            try
            {
                PlaybackRequest.From((n, d) => n == PlaybackRequest.ExtraTrials ? 0 : d, n => null, files, 5);
                Check(false, "trials = 0 is refused");
            }
            catch (ArgumentException e)
            {
                Check(e.Message.Contains("extra trials = 0"), e.Message);
                run.Refuse(Path.Combine(files, "out"), e.Message);
                Check(Status(Path.Combine(files, "out")).StartsWith("failed extra trials = 0"), Status(Path.Combine(files, "out")));
            }
            PlaybackStep dup = run.Launch(r);
            run.Started(dup.Token);
            foreach (long t in new long[] { 100, 100, 200, 150, 300 }) run.OnFrame(t, PoseAt(0), PlaybackProgress.Ok);
            run.OnFrame(400, PoseAt(0), PlaybackProgress.Finished);
            Check(TumLines(Path.Combine(r.Output, "trajectory_0.txt")) == 3, "duplicate and older frames skipped");
            PlaybackRequest byHand = PlaybackRequest.From((n, d) => d, n => null, files, 5);
            Check(byHand.Trials == 5 && byHand.First == 0 && byHand.Recording == Path.Combine(files, "recording.mp4") && byHand.Output == Path.Combine(files, "out"), "defaults");
        }
    }

    static readonly string[] JsonCases =
    {
        "http://192.168.0.10:8000", "http://h/\"quoted\"", "back\\slash\\", "line\nbreak\r\ttab",
        "\u0000\u0001\u001f control", "ünïcödé ✓ \u2028 separators \u2029", "{\"injected\":true}",
    };

    static void Json()
    {
        foreach (string url in JsonCases)
        {
            string doc = new SitarJson().Add("convention", "unity").Add("server_url", url).ToString();
            // libsitar's config parser takes every one of them.
            new SitarSession(doc).Dispose();
            string hex = string.Concat(Encoding.UTF8.GetBytes(url).Select(b => b.ToString("x2")));
            Console.WriteLine("JSON " + hex + " " + doc);
        }
        string options = new SitarJson().Add("trials", 10).Add("setting", "trim_mean_30").Add("x", 0.5).Add("ok", true).Add("none", (string)null).ToString();
        Check(options == "{\"trials\":10,\"setting\":\"trim_mean_30\",\"x\":0.5,\"ok\":true,\"none\":null}", options);
        try
        {
            new SitarJson().Add("x", double.NaN);
            Check(false, "NaN is refused");
        }
        catch (ArgumentException e)
        {
            Check(e.Message.Contains("field x"), e.Message);
        }
    }

    /// <summary>Edge arrows from the real library's guide, the kineticon, the layer colours.</summary>
    static void VenueLayer()
    {
        string map = "{\"id\":\"v0123456789abcdef\",\"name\":\"Hall\",\"anchor\":\"hall\",\"cell_m\":0.25,"
            + "\"convention\":\"unity\",\"unit\":\"m\",\"sessions\":[],\"cells\":["
            + "{\"center\":[0.0,1.0,0.0],\"kind\":\"surface\",\"sessions\":2,\"subtrajectories\":3,\"error_m\":0.3,\"class\":\"high\",\"directions\":[0,0,3,0,0,0,0,0]},"
            + "{\"center\":[3.0,1.0,0.0],\"kind\":\"surface\",\"sessions\":2,\"subtrajectories\":3,\"error_m\":0.2,\"class\":\"high\",\"directions\":[0,0,3,0,0,0,0,0]}]}";
        using (var s = new SitarSession())
        {
            s.Start(0, new Pose(0, 0, 0, 0, 0, 0, 1));
            s.LoadVenue(map);
            s.Anchor(1, "hall", new Pose(0, 0, 2, 0, 0, 0, 1), Tracking.Full);
            // Camera at (0, 1, 0) looking +Z: cell 0 (0, 1, 2) ahead; cell 1 (3, 1, 2) off to the right.
            var guides = new Guide[4];
            int n = s.Guide(new Pose(0, 1, 0, 0, 0, 0, 1), 60, 1080, 1920, 40, guides);
            Check(n == 2 && guides[0].OnScreen && !guides[1].OnScreen, "one target on screen, one off");
            var arrows = new EdgeArrow[4];
            int k = VenueView.EdgeArrows(guides, n, 1920, arrows);
            Check(k == 1 && arrows[0].Index == 1, "one arrow, for the off-screen cell");
            Check(Math.Abs(arrows[0].X - 1040) < 1e-3 && Math.Abs(arrows[0].Y - 960) < 1e-3, "at the right end of the ellipse: " + arrows[0].X + ", " + arrows[0].Y);
            Check(Math.Abs(arrows[0].RotationDeg) < 1e-6, "pointing right");
            // Above and behind: Unity's y is up, its rotation counter-clockwise (+90°).
            guides[1] = new Guide();
            n = s.Guide(new Pose(0, -5, 0, 0, 1, 0, 0), 60, 1080, 1920, 40, guides);
            k = VenueView.EdgeArrows(guides, n, 1920, arrows);
            Check(k == 2 && Math.Abs(arrows[0].RotationDeg - 90) < 1e-3 && arrows[0].Y > 960, "up and behind: " + arrows[0].RotationDeg + " at y " + arrows[0].Y);
            Check(VenueView.EdgeArrows(guides, n, 1920, new EdgeArrow[1]) == 1, "as many arrows as fit");
        }

        var kin = new Kineticon { PulseSeconds = 3, PulsesPerSecond = 1.5, Amplitude = 0.4 };
        Check(kin.Scale(2, false, 10) == 1, "not seen yet: still");
        Check(kin.Scale(2, true, 10) == 1, "first seen: the pulse starts at rest");
        Check(kin.Scale(2, true, 10 + 1.0 / 3) > 1.3, "a third of a second later: swung out");
        Check(kin.Scale(2, false, 11) > 1, "keeps pulsing out of view within its first seconds");
        Check(kin.Scale(2, true, 13.01) == 1, "after its first seconds: still");
        Check(kin.Scale(0, true, 13.01) == 1 && kin.Scale(0, true, 13.5) > 1, "each marker has its own clock");
        kin.Reset();
        Check(kin.Scale(2, true, 20) == 1 && kin.Scale(2, true, 20 + 1.0 / 3) > 1.3, "reset: pulses again");

        float r, g, b, a, a2;
        VenueView.CellColor(CellKind.Surface, ErrorClass.High, out r, out g, out b, out a);
        Check(r > 0.8f && g < 0.2f && a > 0.3f && a < 1, "high surface: translucent red");
        VenueView.CellColor(CellKind.Path, ErrorClass.High, out r, out g, out b, out a2);
        Check(a2 < a, "path cells: a fainter trail");
    }

    static int Main(string[] args)
    {
        string work = args[0];
        EveryTrialIsWritten(work);
        PauseDropsTheUnfinishedTrial(work);
        ASecondLaunchReplacesTheRunningOne(work);
        FailuresReachTheStatusFile(work);
        Json();
        VenueLayer();
        Console.WriteLine("PASSED " + checks + " checks");
        return 0;
    }
}
