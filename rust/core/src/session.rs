//! The on-device session: recorder cadence, depth samples, results, markers, render plan.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::depth::sample_surface;
use crate::markers::{MarkerCandidate, select_markers};
use crate::{
    DepthImage, DepthSample, DisplayRotation, Error, ErrorClass, Intrinsics, InvalidDepth, Marker,
    Pose, RenderPlan, Results, SessionConfig,
};

/// What a frame asks of the app (bit set; the C ABI's `out_flags`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FrameFlags(pub u32);

impl FrameFlags {
    /// An ordinary frame: nothing to do.
    pub const NONE: FrameFlags = FrameFlags(0);
    /// A sub-trajectory midpoint: the pose was logged; give a depth sample now.
    pub const MIDPOINT: FrameFlags = FrameFlags(1);
    /// A sub-trajectory endpoint: the pose was logged and a sub-trajectory closed.
    pub const ENDPOINT: FrameFlags = FrameFlags(2);

    /// Whether the midpoint bit is set.
    pub fn is_midpoint(&self) -> bool {
        self.0 & Self::MIDPOINT.0 != 0
    }

    /// Whether the endpoint bit is set.
    pub fn is_endpoint(&self) -> bool {
        self.0 & Self::ENDPOINT.0 != 0
    }
}

/// Totals of a recording (see ARCHITECTURE.md "Counting").
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Summary {
    /// Number of `frame` calls (start and stop are not frames).
    pub frames: u32,
    /// Midpoints reached.
    pub midpoints: u32,
    /// Completed sub-trajectories (endpoint reached).
    pub subtrajectories: u32,
    /// Midpoints with a valid depth sample.
    pub depth_samples: u32,
    /// Stop timestamp minus start timestamp (seconds).
    pub duration_s: f64,
    /// Path through the start pose, every frame pose and the stop pose (metres).
    pub length_m: f64,
    /// Mean distance along the ray of the valid depth samples (metres; 0 without any).
    pub mean_depth_m: f64,
}

/// Where a session is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SessionState {
    /// Created, not started.
    #[default]
    Idle,
    /// Between `start` and `stop`.
    Recording,
    /// Stopped; results can be attached.
    Stopped,
}

/// A logged pose: the start pose, a midpoint or an endpoint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoggedPose {
    /// Timestamp (ns).
    pub t_ns: i64,
    /// Frame number counted from the start call (frame 0).
    pub frame: u32,
    /// World-from-camera pose.
    pub pose: Pose,
    /// Path length from the start through every frame up to this one (metres).
    pub path_m: f64,
}

/// The depth sample of a midpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DepthStatus {
    /// No depth was given for this midpoint.
    Missing,
    /// A depth image was given but unusable at the sample pixel.
    Invalid(InvalidDepth),
    /// A valid surface sample.
    Valid(DepthSample),
}

impl DepthStatus {
    /// The sample, if valid.
    pub fn sample(&self) -> Option<&DepthSample> {
        match self {
            Self::Valid(s) => Some(s),
            _ => None,
        }
    }
}

/// Sub-trajectory `index`: frames `index·n … index·n + n` after the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubTrajectory {
    /// Index, from 0; always equal to the position in [`Session::subtrajectories`].
    pub index: u32,
    /// Timestamp of its first frame (the key of its result window).
    pub start_ns: i64,
    /// Timestamp of its midpoint.
    pub mid_ns: i64,
    /// Timestamp of its endpoint, once reached.
    pub end_ns: Option<i64>,
    /// The midpoint's depth sample.
    pub depth: DepthStatus,
}

/// The whole on-device session: what the C ABI / JNI wrap one-to-one.
///
/// Life: [`Session::start`] → [`Session::frame`] per camera frame (with
/// [`Session::depth`] when a frame returns [`FrameFlags::MIDPOINT`]) → [`Session::stop`];
/// then [`Session::load_results`], [`Session::markers`], [`Session::render_plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct Session {
    pub(crate) config: SessionConfig,
    pub(crate) state: SessionState,
    pub(crate) frames: u32,
    pub(crate) start: Option<(i64, Pose)>,
    pub(crate) stop: Option<(i64, Pose)>,
    pub(crate) last_t_ns: i64,
    pub(crate) last_position: DVec3,
    pub(crate) length_m: f64,
    /// Start timestamp of the sub-trajectory in progress.
    pub(crate) sub_start_ns: i64,
    /// Every frame interval (ns), for the lookup tolerance.
    pub(crate) frame_intervals_ns: Vec<i64>,
    pub(crate) logged: Vec<LoggedPose>,
    pub(crate) subs: Vec<SubTrajectory>,
    pub(crate) results: Option<Results>,
    /// Half the median frame interval, fixed at stop (and on load).
    pub(crate) tolerance_ns: Option<i64>,
}

/// Frames pre-reserved: ten minutes at 30 fps without regrowth on the frame path.
const RESERVE_FRAMES: usize = 18_000;

impl Session {
    /// A new idle session. The config is used as given (see [`SessionConfig::validate`];
    /// an invalid `subtrajectory_frames` falls back to 10 so the cadence stays defined).
    pub fn new(mut config: SessionConfig) -> Self {
        if config.subtrajectory_frames < 2 || !config.subtrajectory_frames.is_multiple_of(2) {
            config.subtrajectory_frames = 10;
        }
        let logged_per_frame = 2 * RESERVE_FRAMES / config.subtrajectory_frames as usize;
        Self {
            config,
            state: SessionState::Idle,
            frames: 0,
            start: None,
            stop: None,
            last_t_ns: 0,
            last_position: DVec3::ZERO,
            length_m: 0.0,
            sub_start_ns: 0,
            frame_intervals_ns: Vec::with_capacity(RESERVE_FRAMES),
            logged: Vec::with_capacity(logged_per_frame + 1),
            subs: Vec::with_capacity(logged_per_frame / 2 + 1),
            results: None,
            tolerance_ns: None,
        }
    }

    /// The session's config.
    pub fn config(&self) -> &SessionConfig {
        &self.config
    }

    /// Idle, recording or stopped.
    pub fn state(&self) -> SessionState {
        self.state
    }

    /// Starts recording at frame 0 with the given pose.
    pub fn start(&mut self, t_ns: i64, pose: Pose) -> Result<(), Error> {
        if self.state != SessionState::Idle {
            return Err(Error::InvalidState(
                "start: the session was already started",
            ));
        }
        let pose = pose.validated("pose")?;
        self.state = SessionState::Recording;
        self.start = Some((t_ns, pose));
        self.last_t_ns = t_ns;
        self.last_position = pose.position;
        self.sub_start_ns = t_ns;
        self.logged.push(LoggedPose {
            t_ns,
            frame: 0,
            pose,
            path_m: 0.0,
        });
        Ok(())
    }

    /// One camera frame. Returns [`FrameFlags::MIDPOINT`] at frames `k·n + n/2` (give depth
    /// now) and [`FrameFlags::ENDPOINT`] at `k·n + n` (sub-trajectory `k` is complete);
    /// `n = subtrajectory_frames`. Timestamps must increase strictly. Allocation-free except
    /// amortised growth of pre-reserved vectors.
    pub fn frame(&mut self, t_ns: i64, pose: Pose) -> Result<FrameFlags, Error> {
        if self.state != SessionState::Recording {
            return Err(Error::InvalidState(
                "frame: the session is not recording (call start first)",
            ));
        }
        let pose = pose.validated("pose")?;
        if t_ns <= self.last_t_ns {
            return Err(Error::arg(
                "t_ns",
                format!(
                    "{t_ns} does not follow the previous frame ({})",
                    self.last_t_ns
                ),
            ));
        }
        self.frame_intervals_ns.push(t_ns - self.last_t_ns);
        self.length_m += pose.position.distance(self.last_position);
        self.last_position = pose.position;
        self.last_t_ns = t_ns;
        self.frames += 1;
        let n = self.config.subtrajectory_frames;
        let phase = self.frames % n;
        if phase == n / 2 {
            let index = self.frames / n;
            self.logged.push(LoggedPose {
                t_ns,
                frame: self.frames,
                pose,
                path_m: self.length_m,
            });
            self.subs.push(SubTrajectory {
                index,
                start_ns: self.sub_start_ns,
                mid_ns: t_ns,
                end_ns: None,
                depth: DepthStatus::Missing,
            });
            Ok(FrameFlags::MIDPOINT)
        } else if phase == 0 {
            self.logged.push(LoggedPose {
                t_ns,
                frame: self.frames,
                pose,
                path_m: self.length_m,
            });
            if let Some(sub) = self.subs.last_mut() {
                sub.end_ns = Some(t_ns);
            }
            self.sub_start_ns = t_ns;
            Ok(FrameFlags::ENDPOINT)
        } else {
            Ok(FrameFlags::NONE)
        }
    }

    /// Attaches a depth sample (image centre) to the latest midpoint; see [`Session::depth_at`].
    pub fn depth(
        &mut self,
        image: &DepthImage<'_>,
        k: &Intrinsics,
        rotation: DisplayRotation,
    ) -> Result<(), Error> {
        self.depth_at(image, k, rotation, None)
    }

    /// Attaches a depth sample at `pixel` (default: the centre) to the latest midpoint, using
    /// the midpoint's pose. An unusable sample is recorded as invalid (the midpoint keeps its
    /// place) and returned as [`Error::InvalidDepth`]; a retry may replace it. A midpoint that
    /// already has a valid sample is an [`Error::InvalidState`].
    pub fn depth_at(
        &mut self,
        image: &DepthImage<'_>,
        k: &Intrinsics,
        rotation: DisplayRotation,
        pixel: Option<(u32, u32)>,
    ) -> Result<(), Error> {
        if self.state != SessionState::Recording {
            return Err(Error::InvalidState("depth: the session is not recording"));
        }
        let Some(sub) = self.subs.last() else {
            return Err(Error::InvalidState("depth: no midpoint reached yet"));
        };
        if matches!(sub.depth, DepthStatus::Valid(_)) {
            return Err(Error::InvalidState(
                "depth: the latest midpoint already has a depth sample",
            ));
        }
        let mid_pose = self.logged[2 * sub.index as usize + 1].pose;
        let result = sample_surface(image, k, rotation, self.config.convention, &mid_pose, pixel);
        let sub = self.subs.last_mut().expect("checked above");
        match result {
            Ok(sample) => {
                sub.depth = DepthStatus::Valid(sample);
                Ok(())
            }
            Err(Error::InvalidDepth(why)) => {
                sub.depth = DepthStatus::Invalid(why);
                Err(Error::InvalidDepth(why))
            }
            Err(other) => Err(other),
        }
    }

    /// Stops recording and returns the summary.
    pub fn stop(&mut self, t_ns: i64, pose: Pose) -> Result<Summary, Error> {
        if self.state != SessionState::Recording {
            return Err(Error::InvalidState("stop: the session is not recording"));
        }
        let pose = pose.validated("pose")?;
        if t_ns < self.last_t_ns {
            return Err(Error::arg(
                "t_ns",
                format!("{t_ns} is before the last frame ({})", self.last_t_ns),
            ));
        }
        self.length_m += pose.position.distance(self.last_position);
        self.last_position = pose.position;
        self.last_t_ns = t_ns;
        self.stop = Some((t_ns, pose));
        self.state = SessionState::Stopped;
        self.tolerance_ns = Some(self.compute_tolerance_ns());
        Ok(self.make_summary())
    }

    /// The summary once stopped.
    pub fn summary(&self) -> Option<Summary> {
        (self.state == SessionState::Stopped).then(|| self.make_summary())
    }

    fn make_summary(&self) -> Summary {
        let valid: Vec<f64> = self
            .subs
            .iter()
            .filter_map(|s| s.depth.sample())
            .map(|s| s.distance_m)
            .collect();
        let (t0, t1) = (
            self.start.map_or(0, |s| s.0),
            self.stop.map_or(self.last_t_ns, |s| s.0),
        );
        Summary {
            frames: self.frames,
            midpoints: self.subs.len() as u32,
            subtrajectories: self.subs.iter().filter(|s| s.end_ns.is_some()).count() as u32,
            depth_samples: valid.len() as u32,
            duration_s: (t1 - t0) as f64 / 1e9,
            length_m: self.length_m,
            mean_depth_m: if valid.is_empty() {
                0.0
            } else {
                valid.iter().sum::<f64>() / valid.len() as f64
            },
        }
    }

    /// The logged poses: start (frame 0), then every midpoint and endpoint.
    pub fn logged(&self) -> &[LoggedPose] {
        &self.logged
    }

    /// The sub-trajectories reached so far (index = position).
    pub fn subtrajectories(&self) -> &[SubTrajectory] {
        &self.subs
    }

    /// The loaded results, if any.
    pub fn results(&self) -> Option<&Results> {
        self.results.as_ref()
    }

    /// Parses and attaches results (legacy CSV or JSON, see [`Results::parse`]); replaces
    /// earlier ones.
    pub fn load_results(&mut self, csv_or_json: &str) -> Result<(), Error> {
        self.results = Some(Results::parse(csv_or_json)?);
        Ok(())
    }

    /// Half the median frame interval (ns): how far a window start may be from a
    /// sub-trajectory's start timestamp. 0 before any frame.
    pub fn lookup_tolerance_ns(&self) -> i64 {
        self.tolerance_ns
            .unwrap_or_else(|| self.compute_tolerance_ns())
    }

    fn compute_tolerance_ns(&self) -> i64 {
        let mut v = self.frame_intervals_ns.clone();
        if v.is_empty() {
            return 0;
        }
        v.sort_unstable();
        let m = v.len() / 2;
        let median2 = if v.len() % 2 == 1 {
            2 * v[m]
        } else {
            v[m - 1] + v[m]
        };
        median2 / 4
    }

    /// Class and error of the result window whose start is nearest to `t_ns` within the
    /// tolerance; `(Unknown, None)` when there is none or no results are loaded.
    pub fn error_at(&self, t_ns: i64) -> (ErrorClass, Option<f64>) {
        self.error_at_with(t_ns, self.lookup_tolerance_ns())
    }

    fn error_at_with(&self, t_ns: i64, tolerance_ns: i64) -> (ErrorClass, Option<f64>) {
        match self
            .results
            .as_ref()
            .and_then(|r| r.lookup(t_ns, tolerance_ns))
        {
            Some(w) => (self.classify(w.error_m), Some(w.error_m)),
            None => (ErrorClass::Unknown, None),
        }
    }

    fn classify(&self, error_m: f64) -> ErrorClass {
        ErrorClass::classify(
            error_m,
            self.config.medium_threshold_m,
            self.config.high_threshold_m,
        )
    }

    /// Estimated error of sub-trajectory `k` (looked up by its start timestamp).
    pub fn subtrajectory_error(&self, k: u32) -> Option<f64> {
        self.subs
            .get(k as usize)
            .and_then(|s| self.error_at(s.start_ns).1)
    }

    /// Class of sub-trajectory `k`; `Unknown` without a result or for an unknown `k`.
    pub fn subtrajectory_class(&self, k: u32) -> ErrorClass {
        self.subs
            .get(k as usize)
            .map_or(ErrorClass::Unknown, |s| self.error_at(s.start_ns).0)
    }

    /// Errors of all sub-trajectories, in order (one tolerance computation, O(n log m)).
    pub fn subtrajectory_errors(&self) -> Vec<Option<f64>> {
        let tol = self.lookup_tolerance_ns();
        self.subs
            .iter()
            .map(|s| self.error_at_with(s.start_ns, tol).1)
            .collect()
    }

    /// Marker regions (see [`crate::select_markers`]) among the sub-trajectories with a valid
    /// depth sample and a result. Needs results: [`Error::InvalidState`] otherwise.
    pub fn markers(&self) -> Result<Vec<Marker>, Error> {
        if self.results.is_none() {
            return Err(Error::InvalidState("markers: no results loaded"));
        }
        let errors = self.subtrajectory_errors();
        let candidates: Vec<MarkerCandidate> = self
            .subs
            .iter()
            .zip(errors)
            .filter_map(|(s, e)| {
                let sample = s.depth.sample()?;
                Some(MarkerCandidate {
                    subtrajectory: s.index,
                    position: sample.point,
                    normal: sample.normal,
                    error_m: e?,
                })
            })
            .collect();
        Ok(select_markers(&candidates, &self.config))
    }

    /// Whether the mean error over all result windows is ≥ `unreliable_mean_error_m`
    /// ("results may be unreliable"); false without results.
    pub fn results_unreliable(&self) -> bool {
        self.results
            .as_ref()
            .and_then(Results::mean_error_m)
            .is_some_and(|m| m >= self.config.unreliable_mean_error_m)
    }

    /// The render plan of the logged trajectory.
    pub fn render_plan(&self) -> RenderPlan {
        crate::render::build(
            &self.logged,
            self.config.subtrajectory_frames,
            self.config.frustum_spacing_m,
            self.stop.map(|s| s.1),
        )
    }

    /// The logged poses (start, midpoints, endpoints) as TUM text, integer nanoseconds.
    pub fn trajectory_tum(&self) -> String {
        crate::tum::to_tum(self.logged.iter().map(|l| (l.t_ns, &l.pose)))
    }
}
