// Host test of SitarSession.cs + NativeMethods.g.cs against the host-built
// libsitar.so (run by tests/tests/bindings_csharp.rs with mcs + mono): a whole
// session and every error path. Unity ignores this folder (its name ends in ~).
// Args: <expected version> <temp dir>. Prints "PASSED n checks" on success.
using System;
using System.IO;
using System.Linq;
using System.Net;
using System.Net.Sockets;
using System.Threading;
using Sitar;

static class HostTest
{
    static int checks;
    const long FrameNs = 33333333;
    const double StepM = 0.1;
    static readonly double[] Errors = { 0.01, 0.12, 0.06, 0.01, 0.2, 0.03 };
    const int W = 160, H = 120;
    static readonly Intrinsics K = new Intrinsics(150, 150, 80, 60);

    static void Check(bool condition, string what)
    {
        checks++;
        if (!condition) throw new Exception("check failed: " + what);
    }

    static void Near(double a, double b, string what, double eps = 1e-9)
    {
        Check(Math.Abs(a - b) <= eps, what + ": " + a + " vs " + b);
    }

    static void ExpectSitar(SitarErrorCode code, string needle, Action action)
    {
        try
        {
            action();
        }
        catch (SitarException e)
        {
            Check(e.Code == code, "expected " + code + ", got " + e.Code + ": " + e.Message);
            Check(e.Message.Contains(needle), "message '" + e.Message + "' should mention '" + needle + "'");
            return;
        }
        throw new Exception("expected SitarException(" + code + ") mentioning '" + needle + "'");
    }

    static Pose PoseAt(long frame)
    {
        return new Pose(frame * StepM, 1.5, 0, 0, 0, 0, 1);
    }

    static ErrorClass ClassOf(double e)
    {
        return e >= 0.10 ? ErrorClass.High : e >= 0.05 ? ErrorClass.Medium : ErrorClass.Low;
    }

    static string ResultsCsv()
    {
        var sb = new System.Text.StringBuilder("start,error\n");
        for (int k = 0; k < Errors.Length; k++) sb.Append(10L * k * FrameNs).Append(',').Append(Errors[k].ToString(System.Globalization.CultureInfo.InvariantCulture)).Append('\n');
        return sb.ToString();
    }

    /// <summary>Results JSON as the backend writes it, one window per 10-frame sub-trajectory.</summary>
    static string ResultsJson(int windowFrames, string relation, string unit, double[] errors)
    {
        string key = unit == "deg" ? "error_deg" : "error_m";
        var windows = errors.Select((e, k) => "{\"start\":" + (10L * k * FrameNs) + ",\"" + key + "\":" + e.ToString(System.Globalization.CultureInfo.InvariantCulture) + ",\"pairs\":3}");
        return "{\"version\":1,\"trials\":3,\"window_frames\":" + windowFrames + ",\"pose_relation\":\"" + relation + "\",\"unit\":\"" + unit + "\",\"windows\":[" + string.Join(",", windows) + "]}";
    }

    static Summary Record(SitarSession s)
    {
        var depth = Enumerable.Repeat((ushort)2000, W * H).ToArray();
        s.Start(0, PoseAt(0));
        for (long i = 1; i <= 60; i++)
        {
            uint flags = s.Frame(i * FrameNs, PoseAt(i));
            uint expected = i % 10 == 5 ? SitarSession.Midpoint : i % 10 == 0 ? SitarSession.Endpoint : 0u;
            Check(flags == expected, "flags of frame " + i + ": " + flags);
            if (flags == SitarSession.Midpoint) s.Depth(depth, W, H, W * 2, K, 0);
        }
        return s.Stop(61 * FrameNs, PoseAt(61));
    }

    static void WholeSession(string tmp)
    {
        var s = new SitarSession("{\"convention\":\"unity\"}");
        Summary sum = Record(s);
        Check(sum.Frames == 60 && sum.Midpoints == 6 && sum.Subtrajectories == 6 && sum.DepthSamples == 6, "counts");
        Near(sum.DurationS, 61.0 * FrameNs / 1e9, "duration");
        Near(sum.LengthM, 6.1, "length", 1e-12);
        Near(sum.MeanDepthM, 2.0, "mean depth");
        Check(s.GetSummary().Equals(sum), "summary again");

        ExpectSitar(SitarErrorCode.InvalidState, "", () => s.Markers());
        Check(s.Results().Length == 6 && s.Results().All(r => r.ErrorM == null && r.ErrorClass == ErrorClass.Unknown), "unknown before results");
        double? err;
        Check(s.ErrorAt(10 * FrameNs, out err) == ErrorClass.Unknown && err == null, "no results yet");

        s.LoadResults(ResultsCsv());
        for (int k = 0; k < Errors.Length; k++)
        {
            Check(s.ErrorAt(10L * k * FrameNs, out err) == ClassOf(Errors[k]) && err == Errors[k], "errorAt sub " + k);
            Check(s.SubtrajectoryClass((uint)k) == ClassOf(Errors[k]), "class of sub " + k);
        }
        Check(s.ErrorAt(1000 * FrameNs, out err) == ErrorClass.Unknown && err == null, "far from any window");
        SubtrajectoryResult[] results = s.Results();
        Check(results.Length == Errors.Length, "results of every sub-trajectory");
        for (int k = 0; k < results.Length; k++)
        {
            Check(results[k].Subtrajectory == k && results[k].ErrorM == Errors[k] && results[k].ErrorClass == ClassOf(Errors[k]), "result " + k);
        }
        Check(!s.ResultsUnreliable(), "reliable");

        Marker[] markers = s.Markers().OrderBy(m => m.Subtrajectory).ToArray();
        Check(markers.Select(m => m.Subtrajectory).SequenceEqual(new uint[] { 1, 2, 4 }), "marker subs");
        foreach (Marker m in markers)
        {
            Check(m.ErrorM == Errors[m.Subtrajectory], "marker error");
            Check(m.ErrorClass == ClassOf(Errors[m.Subtrajectory]), "marker class");
            Near(m.Px, (10 * m.Subtrajectory + 5) * StepM, "marker x");
            Near(m.Py, 1.5, "marker y");
            Near(m.Pz, 2.0, "marker z");
            Near(m.Nz, -1.0, "normal faces the camera");
        }

        RenderPlan plan = s.GetRenderPlan();
        Check(plan.Segments.Length > 0, "segments");
        foreach (Segment g in plan.Segments) Check(g.ErrorClass == ClassOf(Errors[g.Subtrajectory]), "segment class");
        Check(plan.Start.HasValue && plan.Start.Value.Equals(PoseAt(0)), "start " + plan.Start);
        Check(plan.Stop.HasValue && plan.Stop.Value.Equals(PoseAt(61)), "stop " + plan.Stop);

        string tum = s.TrajectoryTum();
        Check(tum.Split('\n').Count(l => l.Length > 0) == 13, "13 logged poses:\n" + tum);

        string folder = Path.Combine(tmp, "csharp-session");
        s.Save(folder);
        using (var loaded = SitarSession.Load(folder))
        {
            Check(loaded.GetSummary().Equals(sum), "loaded summary");
            Check(loaded.ErrorAt(40 * FrameNs, out err) == ErrorClass.High && err == 0.2, "loaded results");
        }

        s.Dispose();
        s.Dispose(); // harmless
        ExpectSitar(SitarErrorCode.InvalidHandle, "handle 0", () => s.GetSummary());
        ExpectSitar(SitarErrorCode.InvalidHandle, "handle 0", () => s.Frame(1, PoseAt(1)));
    }

    static void ErrorPaths()
    {
        ExpectSitar(SitarErrorCode.Parse, "", () => new SitarSession("{"));
        ExpectSitar(SitarErrorCode.Parse, "bogus", () => new SitarSession("{\"bogus\": 1}"));
        ExpectSitar(SitarErrorCode.Null, "config_json", () => new SitarSession(null));
        using (var s = new SitarSession())
        {
            ExpectSitar(SitarErrorCode.InvalidState, "start", () => s.Frame(FrameNs, PoseAt(1)));
            s.Start(0, PoseAt(0));
            ExpectSitar(SitarErrorCode.InvalidArgument, "pose", () => s.Frame(FrameNs, new Pose(double.NaN, 0, 0, 0, 0, 0, 1)));
            for (long i = 1; i <= 5; i++) s.Frame(i * FrameNs, PoseAt(i));
            ExpectSitar(SitarErrorCode.InvalidArgument, "needs", () => s.Depth(new ushort[W * H - 1], W, H, W * 2, K, 0));
            ExpectSitar(SitarErrorCode.Null, "depth_mm", () => s.Depth(IntPtr.Zero, W, H, W * 2, K, 0));
            ExpectSitar(SitarErrorCode.InvalidArgument, "45", () => s.Depth(new ushort[W * H], W, H, W * 2, K, 45));
            // The camera image at the midpoint, the bad inputs, then its evidence.
            byte[] luma = Enumerable.Range(0, W * H).Select(i => (byte)(i % W < W / 2 ? 40 : 200)).ToArray();
            s.Image(luma, W, H, W, 270);
            ExpectSitar(SitarErrorCode.InvalidArgument, "needs", () => s.Image(new byte[W * H - 1], W, H, W, 0));
            ExpectSitar(SitarErrorCode.Null, "luma", () => s.Image(IntPtr.Zero, W, H, W, 0));
            ExpectSitar(SitarErrorCode.InvalidArgument, "row_stride_bytes", () => s.Image(luma, W, H, W - 1, 0));
            ExpectSitar(SitarErrorCode.InvalidArgument, "display_rotation", () => s.Image(luma, W, H, W, 45));
            Evidence ev = s.SubtrajectoryEvidence(0);
            Check(ev.HasImage && ev.ThumbnailHeight >= ev.ThumbnailWidth, "evidence of the portrait image");
            Near(ev.MeanBrightness, 120.0, "mean brightness");
            byte[] jpeg = s.Thumbnail(0);
            Check(jpeg.Length > 100 && jpeg[0] == 0xFF && jpeg[1] == 0xD8, "thumbnail is a JPEG");
            ExpectSitar(SitarErrorCode.InvalidArgument, "7", () => s.SubtrajectoryEvidence(7));
            ExpectSitar(SitarErrorCode.Parse, "line 2", () => s.LoadResults("start,error\n12,abc\n"));
            ExpectSitar(SitarErrorCode.Null, "csv_or_json", () => s.LoadResults(null));
            ExpectSitar(SitarErrorCode.Panic, "on purpose", () => Native.Check(NativeMethods.sitar_testing_panic()));
            Check(s.Frame(6 * FrameNs, PoseAt(6)) == 0, "frame after a panic");
        }
        ExpectSitar(SitarErrorCode.InvalidHandle, "session handle", () => Native.Check(NativeMethods.sitar_session_free(12345)));
    }

    static void Playback(string tmp)
    {
        var p = new PlaybackLogger("{\"convention\":\"arcore\"}");
        for (long i = 0; i < 3; i++) p.Log(1000 + i * FrameNs, PoseAt(i));
        Check(p.Count == 3, "logged 3");
        string dir = Path.Combine(tmp, "logs");
        p.Write(dir, 4);
        Check(File.ReadAllLines(Path.Combine(dir, "trajectory_4.txt")).Length == 3, "3 lines");
        p.Dispose();
        p.Dispose();
        ExpectSitar(SitarErrorCode.InvalidHandle, "playback handle", () => p.Tum());
    }

    static void Upload(string tmp)
    {
        using (var s = new SitarSession())
        {
            string rec = Path.Combine(tmp, "rec.mp4");
            File.WriteAllText(rec, "not really an mp4");
            ExpectSitar(SitarErrorCode.InvalidArgument, "server_url", () => s.Upload(rec));
            var closed = new TcpListener(IPAddress.Loopback, 0);
            closed.Start();
            int port = ((IPEndPoint)closed.LocalEndpoint).Port;
            closed.Stop();
            using (var job = s.Upload(rec, "{\"server_url\":\"http://127.0.0.1:" + port + "\",\"trials\":3}"))
            {
                DateTime deadline = DateTime.UtcNow.AddSeconds(60);
                UploadProgress p = job.Progress();
                while (!p.Finished && DateTime.UtcNow < deadline)
                {
                    Thread.Sleep(20);
                    p = job.Progress();
                }
                Check(p.State == UploadState.Failed && p.ErrorCode == SitarErrorCode.Network, "upload to a closed port: " + p.State + " " + p.ErrorCode);
                Check(job.Message().Contains("127.0.0.1"), job.Message());
            }
            var silent = new TcpListener(IPAddress.Loopback, 0);
            silent.Start();
            int silentPort = ((IPEndPoint)silent.LocalEndpoint).Port;
            var job2 = s.Upload(rec, "{\"server_url\":\"http://127.0.0.1:" + silentPort + "\",\"trials\":3}");
            job2.Cancel();
            Check(job2.Progress().State == UploadState.Cancelled, "cancelled at once");
            job2.Dispose();
            job2.Dispose();
            silent.Stop();
        }
    }

    static ErrorClass DegreeClassOf(double e)
    {
        return e >= 4.0 ? ErrorClass.High : e >= 2.0 ? ErrorClass.Medium : ErrorClass.Low;
    }

    static void WindowSettings(string tmp)
    {
        // angle_deg: classes from the degree thresholds (2°, 4°), markers from thresholds_deg.
        using (var s = new SitarSession("{\"convention\":\"unity\",\"pose_relation\":\"angle_deg\"}"))
        {
            Record(s);
            double[] degrees = { 1.0, 5.0, 3.0, 0.5, 8.0, 2.5 };
            s.LoadResults(ResultsJson(10, "angle_deg", "deg", degrees));
            double? err;
            for (int k = 0; k < degrees.Length; k++)
            {
                Check(s.ErrorAt(10L * k * FrameNs, out err) == DegreeClassOf(degrees[k]) && err == degrees[k], "degrees at sub " + k);
            }
            // ≥ 4° first (subs 1, 4), then ≥ 2° (sub 2); in metres all six would pass 0.10.
            Marker[] markers = s.Markers().OrderBy(m => m.Subtrajectory).ToArray();
            Check(markers.Select(m => m.Subtrajectory).SequenceEqual(new uint[] { 1, 2, 4 }), "degree markers");
            Check(markers.Select(m => m.ErrorClass).SequenceEqual(new[] { ErrorClass.High, ErrorClass.Medium, ErrorClass.High }), "degree marker classes");
            Check(!s.ResultsUnreliable(), "a mean of 3.3° is below 8°");
            // Results that cannot be looked up here are refused, naming both values; the old ones stay.
            ExpectSitar(SitarErrorCode.InvalidArgument, "window_frames 20", () => s.LoadResults(ResultsJson(20, "angle_deg", "deg", degrees)));
            ExpectSitar(SitarErrorCode.InvalidArgument, "pose_relation trans_part", () => s.LoadResults(ResultsCsv()));
            Check(s.ErrorAt(10 * FrameNs, out err) == ErrorClass.High && err == 5.0, "earlier results kept");
            // Upload options must fit the session config.
            string rec = Path.Combine(tmp, "window.mp4");
            File.WriteAllText(rec, "not really an mp4");
            ExpectSitar(SitarErrorCode.InvalidArgument, "subtrajectory_frames 10", () => s.Upload(rec, "{\"server_url\":\"http://127.0.0.1:9\",\"window_frames\":20}"));
            ExpectSitar(SitarErrorCode.Parse, "angle_rad", () => s.Upload(rec, "{\"server_url\":\"http://127.0.0.1:9\",\"pose_relation\":\"angle_rad\"}"));
        }
        ExpectSitar(SitarErrorCode.Parse, "pose_relation", () => new SitarSession("{\"pose_relation\":\"angle_rad\"}"));
        ExpectSitar(SitarErrorCode.Parse, "medium_threshold_deg", () => new SitarSession("{\"medium_threshold_deg\":\"2\"}"));

        // 20-frame sub-trajectories take 20-frame windows.
        using (var s = new SitarSession("{\"subtrajectory_frames\":20}"))
        {
            s.Start(0, PoseAt(0));
            for (long i = 1; i <= 40; i++) s.Frame(i * FrameNs, PoseAt(i));
            s.Stop(41 * FrameNs, PoseAt(41));
            string windows = "{\"start\":0,\"error_m\":0.02},{\"start\":" + (20 * FrameNs) + ",\"error_m\":0.3}";
            s.LoadResults("{\"window_frames\":20,\"windows\":[" + windows + "]}");
            Check(s.Results().Select(r => r.ErrorClass).SequenceEqual(new[] { ErrorClass.Low, ErrorClass.High }), "20-frame results");
            ExpectSitar(SitarErrorCode.InvalidArgument, "subtrajectory_frames 20", () => s.LoadResults("{\"window_frames\":10,\"windows\":[" + windows + "]}"));
        }
    }

    static string Num(double v)
    {
        return v.ToString("R", System.Globalization.CultureInfo.InvariantCulture);
    }

    /// <summary>
    /// Calibrated results as the backend writes them: per window the calibrated error, its
    /// interval and the raw value, keys in alphabetical order; a NaN upper bound leaves the
    /// window without an interval.
    /// </summary>
    static string CalibratedJson(double[] errors, double[] lowers, double[] uppers)
    {
        var windows = errors.Select((e, k) =>
        {
            long start = 10L * k * FrameNs;
            string head = "{\"start\":" + start + ",\"end\":" + (start + 10 * FrameNs);
            if (double.IsNaN(uppers[k]))
                return head + ",\"error_m\":" + Num(e) + ",\"pairs\":3,\"raw_m\":null,\"spread_m\":0.01}";
            return head + ",\"class\":\"low\",\"error_m\":" + Num(e) + ",\"lower_m\":" + Num(lowers[k]) + ",\"pairs\":3,\"raw_m\":"
                + Num(e / 2) + ",\"spread_m\":0.01,\"upper_m\":" + Num(uppers[k]) + "}";
        });
        return "{\"version\":1,\"setting\":\"trim_mean_30\",\"trials\":3,\"time_unit\":\"ns\",\"pose_relation\":\"trans_part\",\"window_frames\":10,\"unit\":\"m\",\"calibration\":\"pixel7-arcore\",\"windows\":["
            + string.Join(",", windows) + "]}";
    }

    static void CalibratedResults()
    {
        double[] errors = { 0.01, 0.12, 0.03, 0.015, 0.025, 0.03 };
        double[] lowers = { 0.005, 0.05, 0.01, 0.005, 0.01, 0.0 };
        double[] uppers = { 0.02, 0.3, 0.15, 0.12, 0.04, double.NaN };
        string json = CalibratedJson(errors, lowers, uppers);
        ErrorClass low = ErrorClass.Low, high = ErrorClass.High;
        double? err;

        // classify_by "estimate" (the default): the errors colour and place markers.
        using (var s = new SitarSession("{\"convention\":\"unity\"}"))
        using (var cautious = new SitarSession("{\"convention\":\"unity\",\"classify_by\":\"upper\"}"))
        {
            Record(s);
            Check(s.BoundsAt(0) == null && s.ResultsCalibration() == null, "no results, no bounds");
            s.LoadResults(json);
            Check(s.ResultsCalibration() == "pixel7-arcore", "calibration " + s.ResultsCalibration());
            for (int k = 0; k < 5; k++)
            {
                ErrorBounds? b = s.BoundsAt(10L * k * FrameNs);
                Check(b.HasValue && b.Value.LowerM == lowers[k] && b.Value.UpperM == uppers[k] && b.Value.RawM == errors[k] / 2, "bounds of sub " + k);
            }
            Check(s.BoundsAt(50 * FrameNs) == null, "sub 5 has no interval");
            Check(s.BoundsAt(1000 * FrameNs) == null, "far from any window");
            Check(s.Results().Select(r => r.ErrorClass).SequenceEqual(new[] { low, high, low, low, low, low }), "estimate classes");
            // 10 cm: sub 1; 5 cm: none; 2 cm: subs 2 and 4.
            Check(s.Markers().Select(m => m.Subtrajectory).OrderBy(k => k).SequenceEqual(new uint[] { 1, 2, 4 }), "estimate markers");

            // classify_by "upper": the upper bounds do (sub 5 has none and keeps its error).
            Record(cautious);
            cautious.LoadResults(json);
            Check(cautious.Results().Select(r => r.ErrorClass).SequenceEqual(new[] { low, high, high, high, low, low }), "upper classes");
            Check(cautious.ErrorAt(30 * FrameNs, out err) == high && err == 0.015, "the error stays the estimate");
            Check(cautious.SubtrajectoryClass(2) == high, "sub 2 high by its upper bound");
            // 10 cm finds subs 1, 2 and 3: sub 3 gets the marker sub 4 had.
            Marker[] markers = cautious.Markers().OrderBy(m => m.Subtrajectory).ToArray();
            Check(markers.Select(m => m.Subtrajectory).SequenceEqual(new uint[] { 1, 2, 3 }), "upper markers");
            Check(markers[2].ErrorClass == high && markers[2].ErrorM == 0.015, "marker 3");
            RenderPlan plan = cautious.GetRenderPlan();
            Check(plan.Segments.Any(g => g.Subtrajectory == 3), "sub 3 has segments");
            Check(plan.Segments.Where(g => g.Subtrajectory == 3).All(g => g.ErrorClass == high), "segments of sub 3 high");
            Check(plan.Segments.Where(g => g.Subtrajectory == 4).All(g => g.ErrorClass == low), "segments of sub 4 low");

            // Uncalibrated results replace them: no bounds, no calibration, the estimate classes.
            cautious.LoadResults(ResultsCsv());
            Check(cautious.BoundsAt(10 * FrameNs) == null && cautious.ResultsCalibration() == null, "uncalibrated");
            Check(cautious.ErrorAt(10 * FrameNs, out err) == high && err == 0.12, "csv class");

            // Bad bounds and a bad choice are errors naming the key.
            ExpectSitar(SitarErrorCode.Parse, "windows[1].lower_m", () => s.LoadResults(json.Replace("\"lower_m\":0.05", "\"lower_m\":0.5")));
            ExpectSitar(SitarErrorCode.Parse, "windows[0].upper_m", () => s.LoadResults(json.Replace("\"upper_m\":0.02", "\"upper_m\":-0.02")));
            Check(s.ResultsCalibration() == "pixel7-arcore", "earlier results kept");
        }
        ExpectSitar(SitarErrorCode.Parse, "classify_by", () => new SitarSession("{\"classify_by\":\"lower\"}"));
    }

    const string VenueMap = "{\"id\":\"v0123456789abcdef\",\"name\":\"Hall\",\"anchor\":\"hall\",\"cell_m\":0.25,"
        + "\"convention\":\"unity\",\"unit\":\"m\",\"sessions\":[],\"cells\":["
        + "{\"center\":[1.0,0.0,0.5],\"kind\":\"path\",\"sessions\":1,\"subtrajectories\":2,\"error_m\":0.02,\"class\":\"low\",\"directions\":[2,0,0,0,0,0,0,0]},"
        + "{\"center\":[0.0,1.0,0.0],\"kind\":\"surface\",\"sessions\":2,\"subtrajectories\":3,\"error_m\":0.3,\"class\":\"high\",\"directions\":[0,0,3,0,0,0,0,0]}]}";

    static void Venue()
    {
        using (var s = new SitarSession())
        {
            double q = Math.Sqrt(0.5);
            // On the floor 2 m ahead, its +X turned 90° about +Y (to −Z).
            var image = new Pose(0, 0, 2, 0, q, 0, q);
            ExpectSitar(SitarErrorCode.InvalidState, "not recording", () => s.Anchor(0, "hall", image, Tracking.Full));
            s.Start(0, PoseAt(0));
            ExpectSitar(SitarErrorCode.InvalidArgument, "anchor_id", () => s.Anchor(1, "", image, Tracking.Full));
            ExpectSitar(SitarErrorCode.InvalidArgument, "anchor_id", () => s.Anchor(1, new string('x', 65), image, Tracking.Full));
            ExpectSitar(SitarErrorCode.InvalidArgument, "pose", () => s.Anchor(1, "hall", new Pose(double.NaN, 0, 2, 0, q, 0, q), Tracking.Full));
            ExpectSitar(SitarErrorCode.InvalidArgument, "tracking", () => s.Anchor(1, "hall", image, (Tracking)5));
            ExpectSitar(SitarErrorCode.Null, "anchor_id", () => s.Anchor(1, null, image, Tracking.Full));
            var cells = new VenueCell[1];
            ExpectSitar(SitarErrorCode.InvalidState, "no venue", () => s.VenueCells(cells));
            s.LoadVenue(VenueMap);
            s.Anchor(1, "hall", image, Tracking.Limited);
            ExpectSitar(SitarErrorCode.InvalidState, "full tracking", () => s.VenueCells(cells));
            s.Anchor(2, "hall", image, Tracking.Full);
            Check(s.VenueCells(cells) == 2 && cells[0].ErrorM == 0, "too small: count only");
            cells = new VenueCell[2];
            Check(s.VenueCells(cells) == 2, "two cells");
            Near(cells[0].Px, 0.5, "cell x", 1e-12);
            Near(cells[0].Pz, 1.0, "cell z", 1e-12);
            Check(cells[0].Kind == CellKind.Path && cells[0].ErrorClass == ErrorClass.Low && cells[0].Sessions == 1, "path cell");
            Check(cells[1].Kind == CellKind.Surface && cells[1].ErrorClass == ErrorClass.High && cells[1].ErrorM == 0.3, "surface cell");
            var guides = new Guide[4];
            Check(s.Guide(new Pose(0, 1, 0, 0, 0, 0, 1), 60, 1080, 1920, 40, guides) == 1, "one target");
            Check(guides[0].OnScreen, "ahead is on screen");
            Near(guides[0].XPx, 540, "centre x");
            Near(guides[0].YPx, 960, "centre y");
            Near(guides[0].DistanceM, 2, "distance");
            s.Guide(new Pose(0.3, 1, 0, 0, 1, 0, 0), 60, 1080, 1920, 40, guides);
            Check(!guides[0].OnScreen && guides[0].XPx > 540, "behind, to the right");
            ExpectSitar(SitarErrorCode.InvalidArgument, "vfov_deg", () => s.Guide(new Pose(0, 0, 0, 0, 0, 0, 1), 0, 1080, 1920, 40, guides));
        }
    }

    // The estimate from one walk: the calibrations are written into the temp dir by
    // tests/tests/bindings_csharp.rs (rust/ffi/tests/support/walk_calibration.rs): error =
    // 0.05 m × (path + 1 mm) / 0.1 m over a 10-frame window, interval ×0.5 … ×2.
    const long WalkFrames = 40;

    /// <summary>x at frame i: 5 mm a frame for 20 frames, 3 cm for 10, 6 cm for 10 (then still).</summary>
    static double WalkX(long i)
    {
        long j = Math.Min(i, WalkFrames);
        return Math.Min(j, 20) * 0.005 + Math.Max(Math.Min(j, 30) - 20, 0) * 0.03 + Math.Max(j - 30, 0) * 0.06;
    }

    static Pose WalkPose(long i)
    {
        return new Pose(WalkX(i), 1.5, 0, 0, 0, 0, 1);
    }

    /// <summary>What the calibration gives the window of 10 frames from frame start.</summary>
    static double WalkError(long start)
    {
        return 0.05 * (WalkX(start + 10) - WalkX(start) + 0.001) / 0.1;
    }

    /// <summary>Records the walk (a wall 2 m ahead at every midpoint) and stops.</summary>
    static void Walk(SitarSession s)
    {
        var depth = Enumerable.Repeat((ushort)2000, 16 * 16).ToArray();
        s.Start(0, WalkPose(0));
        for (long i = 1; i <= WalkFrames; i++)
        {
            if ((s.Frame(i * FrameNs, WalkPose(i)) & SitarSession.Midpoint) != 0) s.Depth(depth, 16, 16, 32, new Intrinsics(15, 15, 8, 8), 0);
        }
        Summary sum = s.Stop((WalkFrames + 1) * FrameNs, WalkPose(WalkFrames));
        Check(sum.Subtrajectories == 4 && sum.DepthSamples == 4, "walk summary");
    }

    static ErrorClass[] Classes(SitarSession s)
    {
        return s.Results().Select(r => r.ErrorClass).ToArray();
    }

    static void WalkEstimate(string tmp)
    {
        string calibration = File.ReadAllText(Path.Combine(tmp, "calibration-walk.json"));
        ErrorClass low = ErrorClass.Low, high = ErrorClass.High;
        var none = new Provenance();

        // Set before the walk: coloured at stop, offline, with the calibration's numbers.
        var s = new SitarSession();
        Check(s.ResultsProvenance().Equals(none), "no results yet");
        s.SetCalibration(calibration);
        Walk(s);
        Check(Classes(s).SequenceEqual(new[] { low, low, high, high }), "walk classes");
        foreach (SubtrajectoryResult r in s.Results()) Near(r.ErrorM.Value, WalkError(10L * r.Subtrajectory), "walk error of sub " + r.Subtrajectory, 1e-12);
        Provenance fromWalk = s.ResultsProvenance();
        Check(fromWalk.Source == ResultSource.Walk && fromWalk.Target == ResultTarget.Live && fromWalk.Runs == 1 && fromWalk.Informative == true && !fromWalk.IsGuess, "from the walk");
        Check(s.ResultsCalibration() == "on_device", "calibration " + s.ResultsCalibration());
        ErrorBounds? bounds = s.BoundsAt(20 * FrameNs);
        Check(bounds.HasValue, "the walk's windows have intervals");
        Near(bounds.Value.UpperM, 2 * WalkError(20), "upper bound", 1e-12);
        Marker[] markers = s.Markers();
        // In time order: sub 2 is the first high place; sub 3 and the low ones lie within 0.5 m of it.
        Check(markers.Length == 1 && markers[0].Subtrajectory == 2 && markers[0].ErrorClass == high, "walk markers");
        // The backend's results replace the walk's.
        s.LoadResults("start,error\n0,0.2\n" + (10 * FrameNs) + ",0.01\n" + (20 * FrameNs) + ",0.01\n" + (30 * FrameNs) + ",0.01\n");
        Check(Classes(s).SequenceEqual(new[] { high, low, low, low }), "backend classes");
        Check(s.ResultsProvenance().Equals(none) && s.ResultsCalibration() == null, "legacy CSV says nothing of its source");
        // A calibration given now keeps them.
        s.SetCalibration(calibration);
        Check(Classes(s).SequenceEqual(new[] { high, low, low, low }), "backend results kept");
        s.Dispose();
        ExpectSitar(SitarErrorCode.InvalidHandle, "handle 0", () => s.SetCalibration(calibration));
        ExpectSitar(SitarErrorCode.InvalidHandle, "handle 0", () => s.ResultsProvenance());

        // Set after the stop: coloured at once; a calibration whose runs do not predict the error says so.
        using (var later = new SitarSession())
        {
            Walk(later);
            Check(Classes(later).All(c => c == ErrorClass.Unknown), "uncoloured without a calibration");
            later.SetCalibration(File.ReadAllText(Path.Combine(tmp, "calibration-guess.json")));
            Check(Classes(later).SequenceEqual(new[] { low, low, high, high }), "coloured at once");
            Provenance guess = later.ResultsProvenance();
            Check(guess.Source == ResultSource.Walk && guess.Informative == false && guess.IsGuess, "a guess");
        }

        // Refused calibrations name what is wrong and change nothing.
        using (var refused = new SitarSession())
        {
            ExpectSitar(SitarErrorCode.Parse, "not a calibration file", () => refused.SetCalibration("{"));
            ExpectSitar(SitarErrorCode.Null, "json", () => refused.SetCalibration(null));
            ExpectSitar(SitarErrorCode.InvalidArgument, "20 window frames", () => refused.SetCalibration(File.ReadAllText(Path.Combine(tmp, "calibration-window20.json"))));
            ExpectSitar(SitarErrorCode.InvalidArgument, "no model for the live error from 1 run", () => refused.SetCalibration(File.ReadAllText(Path.Combine(tmp, "calibration-expected-only.json"))));
            Walk(refused);
            Check(Classes(refused).All(c => c == ErrorClass.Unknown) && refused.ResultsProvenance().Equals(none), "nothing taken");
        }
    }

    static int Main(string[] args)
    {
        Check(SitarSession.Version == args[0], "version " + SitarSession.Version);
        WholeSession(args[1]);
        ErrorPaths();
        Playback(args[1]);
        Upload(args[1]);
        WindowSettings(args[1]);
        CalibratedResults();
        Venue();
        WalkEstimate(args[1]);
        Console.WriteLine("PASSED " + checks + " checks");
        return 0;
    }
}
