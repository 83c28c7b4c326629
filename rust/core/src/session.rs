//! The on-device session: recorder cadence, depth samples, results, markers, render plan.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::depth::sample_surface;
use crate::evidence::{DepthProperties, Evidence, MotionProperties, SessionMedians, likely_causes};
use crate::logged_pose::LoggedPose;
use crate::markers::{MarkerCandidate, select_markers};
use crate::thumbnail::{PixelScratch, downsample_rotated, encode_jpeg};
use crate::venue::{Alignment, AnchorObservation, NotAligned, Tracking, VenueMap, WorldCell};
use crate::{
    DepthImage, DepthSample, DisplayRotation, Error, ErrorClass, Guide, ImageProperties,
    Intrinsics, InvalidDepth, LumaImage, Marker, Pose, RenderPlan, ResultWindow, Results,
    ScreenView, SessionConfig,
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

/// What the app gave at a midpoint besides its pose: the camera image's properties and
/// thumbnail, and how much of the depth window had depth.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MidpointInput {
    /// Properties of the camera image, if one was given.
    pub image: Option<ImageProperties>,
    /// Display-oriented greyscale JPEG thumbnail (empty without an image).
    pub thumbnail: Vec<u8>,
    /// Thumbnail size in display orientation (width, height; 0 without an image).
    pub thumbnail_size: (u32, u32),
    /// Share of pixels with depth in the 5×5 sample window (`None`: no depth image given).
    pub depth_valid_share: Option<f64>,
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
    /// Image and depth-window evidence per sub-trajectory (same index as `subs`).
    pub(crate) inputs: Vec<MidpointInput>,
    /// An image given after start but before the first midpoint: sub-trajectory 0's frames.
    pub(crate) pending_input: Option<MidpointInput>,
    /// Reused buffer of the downsampled thumbnail pixels.
    pub(crate) thumbnail_pixels: PixelScratch,
    pub(crate) results: Option<Results>,
    /// Half the median frame interval, fixed at stop (and on load).
    pub(crate) tolerance_ns: Option<i64>,
    /// A lookup tolerance set by the app, replacing the default.
    pub(crate) tolerance_override_ns: Option<i64>,
    /// The markers of the current results and depth samples (empty without results), kept
    /// so that [`Session::guide_into`] needs no allocation.
    pub(crate) markers: Vec<Marker>,
    /// Every anchor observation, in call order.
    pub(crate) anchors: Vec<AnchorObservation>,
    /// The venue loaded with [`Session::load_venue`], its alignment and its cells in the
    /// world frame.
    pub(crate) venue: Option<LoadedVenue>,
    /// The walk itself: the start pose and every frame's pose (index = frame number), for
    /// the estimate from one walk.
    pub(crate) walk: Vec<(i64, Pose)>,
    /// The calibration given with [`Session::set_calibration`].
    pub(crate) calibration: Option<crate::calibration::Calibration>,
}

/// A venue map and this session's place in it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LoadedVenue {
    pub(crate) map: VenueMap,
    pub(crate) alignment: Result<Alignment, NotAligned>,
    /// The map's cells in this session's world frame (empty while not aligned).
    pub(crate) cells: Vec<WorldCell>,
    /// Observations of its anchor so far, and their number at the last alignment.
    pub(crate) observed: usize,
    pub(crate) aligned_at: usize,
}

impl LoadedVenue {
    fn new(map: VenueMap, anchors: &[AnchorObservation]) -> Self {
        let observed = anchors.iter().filter(|o| o.anchor == map.anchor).count();
        let mut v = Self {
            alignment: Err(NotAligned {
                reason: String::new(),
            }),
            map,
            cells: Vec::new(),
            observed,
            aligned_at: 0,
        };
        v.realign(anchors);
        v
    }

    fn realign(&mut self, anchors: &[AnchorObservation]) {
        self.aligned_at = self.observed;
        self.alignment = crate::venue::align(anchors, &self.map.anchor);
        self.cells = match &self.alignment {
            Ok(a) => crate::venue::world_cells(&self.map, a),
            Err(_) => Vec::new(),
        };
    }
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
            inputs: Vec::with_capacity(logged_per_frame / 2 + 1),
            pending_input: None,
            thumbnail_pixels: PixelScratch::default(),
            results: None,
            tolerance_ns: None,
            tolerance_override_ns: None,
            markers: Vec::new(),
            anchors: Vec::new(),
            venue: None,
            walk: Vec::with_capacity(RESERVE_FRAMES + 1),
            calibration: None,
        }
    }

    /// Like [`Session::new`], but first checks the config ([`SessionConfig::validate`]).
    pub fn try_new(config: SessionConfig) -> Result<Self, Error> {
        config.validate()?;
        Ok(Self::new(config))
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
        self.walk.push((t_ns, pose));
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
    /// `n = subtrajectory_frames`. Timestamps must increase strictly, and a pose so far from the
    /// previous one that the path length overflows is refused. Allocation-free except
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
        let Some(interval) = t_ns.checked_sub(self.last_t_ns) else {
            return Err(Error::arg(
                "t_ns",
                "interval since the previous frame overflows i64",
            ));
        };
        let length_m = self.path_to(pose.position)?;
        self.frame_intervals_ns.push(interval);
        self.walk.push((t_ns, pose));
        self.length_m = length_m;
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
            let input = if self.inputs.is_empty() {
                self.pending_input.take().unwrap_or_default()
            } else {
                MidpointInput::default()
            };
            self.inputs.push(input);
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
        let Some(mid) = self.logged.get(2 * sub.index as usize + 1) else {
            return Err(Error::InvalidState("depth: the midpoint pose is missing"));
        };
        let mid_pose = mid.pose;
        let (px, py) = pixel.unwrap_or_else(|| image.centre());
        let share = depth_window_share(image, px, py);
        if let Some(input) = self.inputs.last_mut() {
            input.depth_valid_share = Some(share);
        }
        let result = sample_surface(image, k, rotation, self.config.convention, &mid_pose, pixel);
        let sub = self.subs.last_mut().expect("checked above");
        match result {
            Ok(sample) => {
                sub.depth = DepthStatus::Valid(sample);
                self.refresh_markers();
                Ok(())
            }
            Err(Error::InvalidDepth(why)) => {
                sub.depth = DepthStatus::Invalid(why);
                Err(Error::InvalidDepth(why))
            }
            Err(other) => Err(other),
        }
    }

    /// Attaches the camera's luminance plane to the latest midpoint (call it when a frame
    /// returns [`FrameFlags::MIDPOINT`], with the same frame's image): measures its
    /// [`ImageProperties`] and keeps a display-oriented JPEG thumbnail (longest side
    /// `thumbnail_px`). A second call for the same midpoint replaces the first; a call after
    /// start but before the first midpoint is kept for sub-trajectory 0 (its frames) unless its
    /// midpoint gets one. With
    /// `"images": false` in the config the call does nothing. Measuring allocates nothing;
    /// the thumbnail is one allocation per midpoint (the JPEG encoder's buffers besides).
    pub fn image(&mut self, image: &LumaImage<'_>, rotation: DisplayRotation) -> Result<(), Error> {
        if self.state != SessionState::Recording {
            return Err(Error::InvalidState("image: the session is not recording"));
        }
        if !self.config.images {
            return Ok(());
        }
        let properties = ImageProperties::measure(image);
        let size = downsample_rotated(
            image,
            self.config.thumbnail_px,
            rotation,
            &mut self.thumbnail_pixels.0,
        );
        let jpeg = encode_jpeg(&self.thumbnail_pixels.0, size.0, size.1)?;
        let input = match self.inputs.last_mut() {
            Some(input) => input,
            None => self.pending_input.insert(MidpointInput::default()),
        };
        input.image = Some(properties);
        input.thumbnail = jpeg;
        input.thumbnail_size = size;
        Ok(())
    }

    /// What the app gave at each midpoint besides its pose (index = sub-trajectory).
    pub fn midpoint_inputs(&self) -> &[MidpointInput] {
        &self.inputs
    }

    /// The JPEG thumbnail of sub-trajectory `k`'s midpoint, if an image was given.
    pub fn thumbnail(&self, k: u32) -> Option<&[u8]> {
        self.inputs
            .get(k as usize)
            .map(|i| i.thumbnail.as_slice())
            .filter(|t| !t.is_empty())
    }

    /// How the camera moved over sub-trajectory `k` (start → midpoint → end, or start →
    /// midpoint while its end is not reached).
    pub fn motion(&self, k: u32) -> Option<MotionProperties> {
        let sub = self.subs.get(k as usize)?;
        let first = 2 * sub.index as usize;
        let last = if sub.end_ns.is_some() {
            first + 2
        } else {
            first + 1
        };
        let poses = self.logged.get(first..=last)?;
        let (a, b) = (poses.first()?, poses.last()?);
        let dt = (b.t_ns - a.t_ns) as f64 / 1e9;
        if dt <= 0.0 {
            return Some(MotionProperties::default());
        }
        let turned: f64 = poses
            .windows(2)
            .map(|w| w[0].pose.rotation.angle_between(w[1].pose.rotation))
            .sum();
        Some(MotionProperties {
            linear_speed_m_s: (b.path_m - a.path_m) / dt,
            angular_speed_deg_s: turned.to_degrees() / dt,
        })
    }

    /// The depth properties of sub-trajectory `k`'s midpoint.
    pub fn depth_properties(&self, k: u32) -> Option<DepthProperties> {
        let sub = self.subs.get(k as usize)?;
        let share = self
            .inputs
            .get(k as usize)
            .and_then(|i| i.depth_valid_share);
        Some(DepthProperties {
            given: !matches!(sub.depth, DepthStatus::Missing),
            valid: sub.depth.sample().is_some(),
            distance_m: sub.depth.sample().map_or(0.0, |s| s.distance_m),
            valid_share: share.unwrap_or(0.0),
        })
    }

    /// The evidence of every sub-trajectory: properties and likely causes, the relative rules
    /// against this session's medians ([`crate::likely_causes`], [`crate::SessionMedians`]).
    pub fn evidence(&self) -> Vec<Evidence> {
        let images: Vec<ImageProperties> = self.inputs.iter().filter_map(|i| i.image).collect();
        let motions: Vec<MotionProperties> = (0..self.subs.len() as u32)
            .filter_map(|k| self.motion(k))
            .collect();
        let medians = SessionMedians::of(&images, &motions);
        (0..self.subs.len() as u32)
            .map(|k| {
                let image = self.inputs.get(k as usize).and_then(|i| i.image);
                let motion = self.motion(k).unwrap_or_default();
                let depth = self.depth_properties(k).unwrap_or_default();
                Evidence {
                    index: k,
                    image,
                    motion,
                    depth,
                    causes: likely_causes(image.as_ref(), &motion, &depth, &medians),
                }
            })
            .collect()
    }

    /// The evidence of sub-trajectory `k` (see [`Session::evidence`]).
    pub fn evidence_of(&self, k: u32) -> Result<Evidence, Error> {
        let n = self.subs.len();
        self.evidence().get(k as usize).copied().ok_or_else(|| {
            Error::arg(
                "index",
                format!("{k} is not a sub-trajectory (there are {n})"),
            )
        })
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
        self.length_m = self.path_to(pose.position)?;
        self.last_position = pose.position;
        self.last_t_ns = t_ns;
        self.stop = Some((t_ns, pose));
        self.state = SessionState::Stopped;
        self.tolerance_ns = Some(self.compute_tolerance_ns());
        if self.results.is_none() {
            // With a calibration, the walk colours itself now, offline; a walk too short for
            // one window simply has no results yet.
            let _ = self.estimate_from_walk();
        }
        self.refresh_markers();
        Ok(self.make_summary())
    }

    /// The path length after moving on to `position`. Finite positions far enough apart
    /// (beyond ~1e154 m) overflow it to infinity, which `session.json` cannot hold: an error.
    #[inline(always)]
    fn path_to(&self, position: DVec3) -> Result<f64, Error> {
        let length_m = self.length_m + position.distance(self.last_position);
        if length_m.is_finite() {
            Ok(length_m)
        } else {
            Err(self.path_overflow(position))
        }
    }

    /// The error of [`Session::path_to`], kept off the frame path.
    #[cold]
    #[inline(never)]
    fn path_overflow(&self, position: DVec3) -> Error {
        Error::arg(
            "pose",
            format!(
                "the path length overflows: position {position} is too far from the previous one ({})",
                self.last_position
            ),
        )
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
            duration_s: (i128::from(t1) - i128::from(t0)) as f64 / 1e9,
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
    /// earlier ones. Results that cannot be looked up for this session are refused with
    /// [`Error::InvalidArgument`] naming both values, and the earlier results stay: windows
    /// of another length than `subtrajectory_frames` (`window_frames`), or errors of another
    /// `pose_relation` than the config's (legacy CSV is `trans_part`).
    pub fn load_results(&mut self, csv_or_json: &str) -> Result<(), Error> {
        let results = Results::parse(csv_or_json)?;
        self.check_results(&results)?;
        self.results = Some(results);
        self.refresh_markers();
        Ok(())
    }

    /// Whether `results` fit this session (see [`Session::load_results`]).
    pub(crate) fn check_results(&self, results: &Results) -> Result<(), Error> {
        let frames = self.config.subtrajectory_frames;
        if let Some(window) = results.window_frames
            && window != frames
        {
            return Err(Error::arg(
                "results",
                format!(
                    "the results are for {window}-frame windows (window_frames {window}), but \
                     this session's sub-trajectories have {frames} frames \
                     (subtrajectory_frames {frames}): they would be looked up wrong"
                ),
            ));
        }
        let configured = self.config.pose_relation;
        if results.relation != configured {
            return Err(Error::arg(
                "results",
                format!(
                    "the results are pose_relation {} (errors in {}), but this session is \
                     configured for pose_relation {configured} (errors in {})",
                    results.relation,
                    results.unit().name(),
                    configured.unit().name()
                ),
            ));
        }
        Ok(())
    }

    /// How far (ns, inclusive) a window start may be from a sub-trajectory's start
    /// timestamp: by default half the median frame interval (0 before any frame).
    pub fn lookup_tolerance_ns(&self) -> i64 {
        self.tolerance_override_ns
            .or(self.tolerance_ns)
            .unwrap_or_else(|| self.compute_tolerance_ns())
    }

    /// Replaces the default lookup tolerance (`None` restores it). Negative is an error.
    pub fn set_lookup_tolerance_ns(&mut self, tolerance_ns: Option<i64>) -> Result<(), Error> {
        if let Some(t) = tolerance_ns
            && t < 0
        {
            return Err(Error::arg("tolerance_ns", format!("{t} is negative")));
        }
        self.tolerance_override_ns = tolerance_ns;
        self.refresh_markers();
        Ok(())
    }

    pub(crate) fn compute_tolerance_ns(&self) -> i64 {
        let mut v = self.frame_intervals_ns.clone();
        if v.is_empty() {
            return 0;
        }
        v.sort_unstable();
        let m = v.len() / 2;
        // i128: two huge intervals must not overflow.
        let median2 = if v.len() % 2 == 1 {
            2 * i128::from(v[m])
        } else {
            i128::from(v[m - 1]) + i128::from(v[m])
        };
        (median2 / 4) as i64
    }

    /// Class and error of the result window whose start is nearest to `t_ns` within the
    /// tolerance; `(Unknown, None)` when there is none or no results are loaded. The error is
    /// the window's ([`ResultWindow::error`]); the class is that of the value the config's
    /// `classify_by` picks ([`crate::ClassifyBy::value`]: the error, or the upper bound).
    pub fn error_at(&self, t_ns: i64) -> (ErrorClass, Option<f64>) {
        match self.result_at(t_ns) {
            Some(w) => (self.classify(w), Some(w.error)),
            None => (ErrorClass::Unknown, None),
        }
    }

    /// The result window [`Session::error_at`] looks up for `t_ns` (nearest start within the
    /// lookup tolerance), with its raw value and interval when the results are calibrated
    /// ([`ResultWindow::raw`], [`ResultWindow::interval`]: `None` otherwise); `None` when no
    /// window is within the tolerance or no results are loaded.
    pub fn result_at(&self, t_ns: i64) -> Option<&ResultWindow> {
        self.results
            .as_ref()
            .and_then(|r| r.lookup(t_ns, self.lookup_tolerance_ns()))
    }

    /// The result window of sub-trajectory `k` (looked up by its start timestamp, as
    /// [`Session::result_at`]); `None` without one or for an unknown `k`.
    pub fn subtrajectory_window(&self, k: u32) -> Option<&ResultWindow> {
        self.subs
            .get(k as usize)
            .and_then(|s| self.result_at(s.start_ns))
    }

    /// The class of a window of the loaded results: the value `classify_by` picks, with the
    /// thresholds of the results' unit.
    fn classify(&self, window: &ResultWindow) -> ErrorClass {
        let unit = self.results.as_ref().map(Results::unit).unwrap_or_default();
        self.config
            .thresholds_for(unit)
            .classify(self.config.classify_by.value(window))
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

    /// Errors of all sub-trajectories, in order (one merge walk, O(n + m)).
    pub fn subtrajectory_errors(&self) -> Vec<Option<f64>> {
        self.subtrajectory_windows()
            .into_iter()
            .map(|w| w.map(|w| w.error))
            .collect()
    }

    /// The result windows of all sub-trajectories, in order (one merge walk, O(n + m)).
    pub fn subtrajectory_windows(&self) -> Vec<Option<&ResultWindow>> {
        let Some(results) = &self.results else {
            return vec![None; self.subs.len()];
        };
        let starts: Vec<i64> = self.subs.iter().map(|s| s.start_ns).collect();
        results.lookup_many(&starts, self.lookup_tolerance_ns())
    }

    /// Marker regions (see [`crate::select_markers`]) among the sub-trajectories with a valid
    /// depth sample and a result. Needs results: [`Error::InvalidState`] otherwise. The
    /// search and the markers' classes use the value `classify_by` picks (the error, or the
    /// upper bound); [`Marker::error_m`] is the window's error either way.
    pub fn markers(&self) -> Result<Vec<Marker>, Error> {
        if self.results.is_none() {
            return Err(Error::InvalidState("markers: no results loaded"));
        }
        let windows = self.subtrajectory_windows();
        let by = self.config.classify_by;
        let candidates: Vec<MarkerCandidate> = self
            .subs
            .iter()
            .zip(&windows)
            .filter_map(|(s, w)| {
                let sample = s.depth.sample()?;
                Some(MarkerCandidate {
                    subtrajectory: s.index,
                    position: sample.point,
                    normal: sample.normal,
                    error_m: by.value(w.as_ref()?),
                })
            })
            .collect();
        let mut markers = select_markers(&candidates, &self.config);
        for m in &mut markers {
            if let Some(Some(w)) = windows.get(m.subtrajectory as usize) {
                m.error_m = w.error;
            }
        }
        Ok(markers)
    }

    /// Whether the mean error over all result windows is ≥ `unreliable_mean_error_m` (or
    /// `unreliable_mean_error_deg` for `angle_deg` results): "results may be unreliable";
    /// false without results.
    pub fn results_unreliable(&self) -> bool {
        self.results.as_ref().is_some_and(|r| {
            r.mean_error()
                .is_some_and(|m| m >= self.config.unreliable_mean_error(r.unit()))
        })
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

    /// Records an observation of anchor image `anchor_id` (1…64 bytes; see
    /// [`crate::venue::check_anchor_id`]): the pose the platform reports for the tracked image
    /// (world-from-image, in the session's convention and world frame; image +X to its
    /// right) and its tracking state. Kept in order, saved as `anchors.csv`; an observation of
    /// the loaded venue's anchor updates the alignment (only `full` ones move it): at once for the
    /// first 32, then whenever their number has grown by 1/32. Calls before
    /// start or after stop are [`Error::InvalidState`].
    pub fn anchor(
        &mut self,
        t_ns: i64,
        anchor_id: &str,
        pose: Pose,
        tracking: Tracking,
    ) -> Result<(), Error> {
        if self.state != SessionState::Recording {
            return Err(Error::InvalidState(
                "anchor: the session is not recording (observations go between start and stop)",
            ));
        }
        crate::venue::check_anchor_id(anchor_id)?;
        let pose = pose.validated("pose")?;
        self.anchors.push(AnchorObservation {
            t_ns,
            anchor: anchor_id.to_owned(),
            pose,
            tracking,
        });
        if let Some(venue) = &mut self.venue
            && venue.map.anchor == anchor_id
        {
            venue.observed += 1;
            // Realigned at once while few observations exist, then whenever their number has
            // grown by 1/32 since the last time: a median over thousands barely moves with one
            // more, and this keeps the work per observation O(log n) amortised.
            if venue.observed - venue.aligned_at > venue.aligned_at / 32 {
                venue.realign(&self.anchors);
            }
        }
        Ok(())
    }

    /// Every anchor observation, in call order.
    pub fn anchors(&self) -> &[AnchorObservation] {
        &self.anchors
    }

    /// Loads a venue map (`map.json` of `GET /v1/venues/{id}/map.json`, see
    /// [`VenueMap::from_json`]) and aligns this session to it from the observations so far.
    /// A map of another convention than the session's is an [`Error::InvalidArgument`] naming
    /// both. Replaces an earlier venue.
    pub fn load_venue(&mut self, map_json: &str) -> Result<(), Error> {
        let map = VenueMap::from_json(map_json)?;
        if map.convention != self.config.convention {
            return Err(Error::arg(
                "map_json",
                format!(
                    "the venue's sessions are in convention {}, this session in {}",
                    map.convention.name(),
                    self.config.convention.name()
                ),
            ));
        }
        self.venue = Some(LoadedVenue::new(map, &self.anchors));
        Ok(())
    }

    /// The loaded venue map, if any.
    pub fn venue(&self) -> Option<&VenueMap> {
        self.venue.as_ref().map(|v| &v.map)
    }

    /// This session's alignment to the loaded venue (`None` without a venue).
    pub fn alignment(&self) -> Option<&Result<Alignment, NotAligned>> {
        self.venue.as_ref().map(|v| &v.alignment)
    }

    /// The loaded venue's cells in this session's world frame, in the map's order.
    /// [`Error::InvalidState`] without a venue or before a `full` observation of its anchor.
    pub fn venue_cells(&self) -> Result<&[WorldCell], Error> {
        match &self.venue {
            None => Err(Error::InvalidState("venue_cells: no venue loaded")),
            Some(v) if v.alignment.is_err() => Err(Error::InvalidState(
                "venue_cells: the venue's anchor has not been seen with full tracking yet",
            )),
            Some(v) => Ok(&v.cells),
        }
    }

    /// The targets [`Session::guide_into`] guides to, in order: each marker (as
    /// [`Session::markers`] lists them once results are loaded, refreshed when results, depth
    /// samples or the lookup tolerance change), then each venue surface cell of class high
    /// in [`Session::venue_cells`] order (none while not aligned).
    pub fn guide_targets(&self) -> impl Iterator<Item = DVec3> + '_ {
        let cells = self.venue.as_ref().map_or(&[][..], |v| v.cells.as_slice());
        self.markers.iter().map(|m| m.position).chain(
            cells
                .iter()
                .filter(|c| {
                    c.kind == crate::venue::CellKind::Surface && c.class == ErrorClass::High
                })
                .map(|c| c.position),
        )
    }

    /// Where each of [`Session::guide_targets`] is shown on `view`'s screen, written to `out`
    /// when it has room for all of them (else nothing is written). Returns their number.
    /// Allocation-free.
    pub fn guide_into(&self, view: &ScreenView, out: &mut [Guide]) -> usize {
        let n = self.guide_targets().count();
        if n <= out.len() {
            for (slot, target) in out.iter_mut().zip(self.guide_targets()) {
                *slot = view.guide(target);
            }
        }
        n
    }

    /// Recomputes the kept markers (after results, a depth sample or the tolerance changed).
    pub(crate) fn refresh_markers(&mut self) {
        self.markers = self.markers().unwrap_or_default();
    }
}

/// Share of the 5×5 window around `(x, y)` with depth (pixels outside the image count as
/// without).
fn depth_window_share(image: &DepthImage<'_>, x: u32, y: u32) -> f64 {
    let mut valid = 0u32;
    for dy in -2i64..=2 {
        for dx in -2i64..=2 {
            let (nx, ny) = (i64::from(x) + dx, i64::from(y) + dy);
            if nx >= 0
                && ny >= 0
                && nx <= i64::from(u32::MAX)
                && ny <= i64::from(u32::MAX)
                && image.get(nx as u32, ny as u32).is_some_and(|d| d != 0)
            {
                valid += 1;
            }
        }
    }
    f64::from(valid) / 25.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Convention;
    use crate::depth::testing::phone_k;
    use glam::DQuat;

    const DT: i64 = 33_333_333;

    fn pose(i: i64) -> Pose {
        Pose::new(DVec3::new(0.1 * i as f64, 1.5, 0.0), DQuat::IDENTITY)
    }

    /// Runs `frames` frames; midpoints get depth unless `skip_depth(k)`.
    fn record(frames: i64, skip_depth: impl Fn(u32) -> bool) -> (Session, Vec<FrameFlags>) {
        record_with(SessionConfig::default(), frames, skip_depth)
    }

    /// [`record`] with another config.
    fn record_with(
        config: SessionConfig,
        frames: i64,
        skip_depth: impl Fn(u32) -> bool,
    ) -> (Session, Vec<FrameFlags>) {
        let wall = vec![2000u16; 256 * 192];
        let image = DepthImage::new(&wall, 256, 192, 512).unwrap();
        let k = Intrinsics {
            cx: 128.0,
            cy: 96.0,
            ..phone_k()
        };
        let mut s = Session::new(config);
        s.start(1_000, pose(0)).unwrap();
        let mut flags = Vec::new();
        for i in 1..=frames {
            let f = s.frame(1_000 + i * DT, pose(i)).unwrap();
            if f.is_midpoint() {
                let sub = s.subtrajectories().len() as u32 - 1;
                if !skip_depth(sub) {
                    s.depth(&image, &k, DisplayRotation::Deg0).unwrap();
                }
            }
            flags.push(f);
        }
        (s, flags)
    }

    #[test]
    fn cadence_midpoints_and_endpoints() {
        let (s, flags) = record(35, |_| false);
        let mids: Vec<usize> = (0..35)
            .filter(|&i| flags[i].is_midpoint())
            .map(|i| i + 1)
            .collect();
        let ends: Vec<usize> = (0..35)
            .filter(|&i| flags[i].is_endpoint())
            .map(|i| i + 1)
            .collect();
        assert_eq!(mids, vec![5, 15, 25, 35]);
        assert_eq!(ends, vec![10, 20, 30]);
        let frames: Vec<u32> = s.logged().iter().map(|l| l.frame).collect();
        assert_eq!(frames, vec![0, 5, 10, 15, 20, 25, 30, 35]);
        let sub1 = s.subtrajectories()[1];
        assert_eq!(
            (sub1.index, sub1.start_ns, sub1.mid_ns, sub1.end_ns),
            (1, 1_000 + 10 * DT, 1_000 + 15 * DT, Some(1_000 + 20 * DT))
        );
        assert_eq!(s.subtrajectories()[3].end_ns, None);
    }

    #[test]
    fn summary_counts() {
        let (mut s, _) = record(42, |k| k == 1);
        assert_eq!(s.summary(), None);
        let summary = s.stop(1_000 + 43 * DT, pose(45)).unwrap();
        assert_eq!(summary.frames, 42);
        assert_eq!(summary.midpoints, 4); // 5, 15, 25, 35
        assert_eq!(summary.subtrajectories, 4); // ends 10, 20, 30, 40
        assert_eq!(summary.depth_samples, 3);
        assert_eq!(summary.duration_s, (43 * DT) as f64 / 1e9);
        assert!((summary.length_m - 4.5).abs() < 1e-12); // 0 → 42 by 0.1, then 4.2 → 4.5
        // Centre pixel on the principal point: distance = depth.
        assert_eq!(summary.mean_depth_m, 2.0);
        assert_eq!(s.summary(), Some(summary));
    }

    #[test]
    fn wrong_state_calls_are_errors() {
        let mut s = Session::new(SessionConfig::default());
        let data = vec![1000u16; 16];
        let image = DepthImage::new(&data, 4, 4, 8).unwrap();
        assert!(matches!(
            s.frame(1, Pose::IDENTITY),
            Err(Error::InvalidState(_))
        ));
        assert!(matches!(
            s.stop(1, Pose::IDENTITY),
            Err(Error::InvalidState(_))
        ));
        assert!(matches!(
            s.depth(&image, &phone_k(), DisplayRotation::Deg0),
            Err(Error::InvalidState(_))
        ));
        s.start(0, Pose::IDENTITY).unwrap();
        assert!(matches!(
            s.start(0, Pose::IDENTITY),
            Err(Error::InvalidState(_))
        ));
        // Depth before any midpoint.
        assert!(matches!(
            s.depth(&image, &phone_k(), DisplayRotation::Deg0),
            Err(Error::InvalidState(_))
        ));
        // Time must move forward; bad poses are rejected; neither counts as a frame.
        assert!(matches!(
            s.frame(0, Pose::IDENTITY),
            Err(Error::InvalidArgument { name: "t_ns", .. })
        ));
        let nan = Pose::new(DVec3::new(f64::NAN, 0.0, 0.0), DQuat::IDENTITY);
        assert!(matches!(
            s.frame(5, nan),
            Err(Error::InvalidArgument { name: "pose", .. })
        ));
        s.frame(5, Pose::IDENTITY).unwrap();
        s.stop(6, Pose::IDENTITY).unwrap();
        assert!(matches!(
            s.frame(7, Pose::IDENTITY),
            Err(Error::InvalidState(_))
        ));
        assert!(matches!(
            s.stop(8, Pose::IDENTITY),
            Err(Error::InvalidState(_))
        ));
        assert!(matches!(
            s.start(9, Pose::IDENTITY),
            Err(Error::InvalidState(_))
        ));
        assert!(matches!(s.markers(), Err(Error::InvalidState(_))));
        assert_eq!(s.summary().unwrap().frames, 1);
    }

    #[test]
    fn invalid_depth_keeps_the_midpoint_slot() {
        let mut s = Session::new(SessionConfig::default());
        let good = vec![2000u16; 256 * 192];
        let mut holey = good.clone();
        holey[96 * 256 + 128] = 0;
        let k = phone_k();
        s.start(0, pose(0)).unwrap();
        for i in 1..=30 {
            if s.frame(i * DT, pose(i)).unwrap().is_midpoint() {
                let data = if i == 15 { &holey } else { &good };
                let image = DepthImage::new(data, 256, 192, 512).unwrap();
                let r = s.depth(&image, &k, DisplayRotation::Deg0);
                if i == 15 {
                    assert!(matches!(
                        r,
                        Err(Error::InvalidDepth(InvalidDepth::NoDepth { x: 128, y: 96 }))
                    ));
                } else {
                    r.unwrap();
                }
            }
        }
        let subs = s.subtrajectories();
        assert_eq!(subs.len(), 3);
        assert!(matches!(
            subs[1].depth,
            DepthStatus::Invalid(InvalidDepth::NoDepth { .. })
        ));
        // Sub-trajectory 2's sample belongs to its own midpoint (frame 25, x = 2.5).
        let p2 = subs[2].depth.sample().unwrap().point;
        assert!((p2.x - (2.5 + 2.0 * (128.0 - 127.5) / 211.0)).abs() < 1e-12);
        assert_eq!(
            subs.iter().map(|s| s.index).collect::<Vec<_>>(),
            vec![0, 1, 2]
        );
        // A second sample for a midpoint that has one is refused.
        let image = DepthImage::new(&good, 256, 192, 512).unwrap();
        assert!(matches!(
            s.depth(&image, &k, DisplayRotation::Deg0),
            Err(Error::InvalidState(_))
        ));
        assert_eq!(s.stop(31 * DT, pose(31)).unwrap().depth_samples, 2);
    }

    #[test]
    fn error_lookup_by_subtrajectory_start() {
        let (mut s, _) = record(40, |_| false);
        s.stop(1_000 + 41 * DT, pose(41)).unwrap();
        assert_eq!(s.lookup_tolerance_ns(), DT / 2);
        // Window starts jittered by less than half a frame; an extra window one frame late.
        let csv = format!(
            "start,error\n{},0.02\n{},0.07\n{},0.2\n{},0.5\n",
            1_000 + 3,
            1_000 + 10 * DT - DT / 2 + 1,
            1_000 + 20 * DT + DT / 2,
            1_000 + 31 * DT,
        );
        s.load_results(&csv).unwrap();
        assert_eq!(s.subtrajectory_class(0), ErrorClass::Low);
        assert_eq!(s.subtrajectory_class(1), ErrorClass::Medium);
        assert_eq!(s.subtrajectory_class(2), ErrorClass::High);
        // Sub 3 starts at frame 30; the nearest window is a whole frame away.
        assert_eq!(s.subtrajectory_class(3), ErrorClass::Unknown);
        assert_eq!(s.subtrajectory_class(99), ErrorClass::Unknown);
        assert_eq!(s.error_at(1_000 + 20 * DT), (ErrorClass::High, Some(0.2)));
        assert_eq!(
            s.subtrajectory_errors(),
            vec![Some(0.02), Some(0.07), Some(0.2), None]
        );
        // A wider tolerance reaches sub 3's window one frame away; None restores the default.
        s.set_lookup_tolerance_ns(Some(DT)).unwrap();
        assert_eq!(s.subtrajectory_class(3), ErrorClass::High);
        assert!(s.set_lookup_tolerance_ns(Some(-1)).is_err());
        s.set_lookup_tolerance_ns(None).unwrap();
        assert_eq!(s.subtrajectory_class(3), ErrorClass::Unknown);
        // Mean 0.1975 < 0.20; adding a bad window tips it.
        assert!(!s.results_unreliable());
        s.load_results(&format!("{csv}{},0.21\n", 1_000 + 50 * DT))
            .unwrap();
        assert!(s.results_unreliable());
        assert!(s.load_results("start,error\n1,x\n").is_err());
    }

    /// A recorded session of `frames` frames with `config`, stopped, and its
    /// sub-trajectories' start stamps.
    fn stopped(config: &str, frames: i64) -> (Session, Vec<i64>) {
        let config = SessionConfig::from_json(config).unwrap();
        let (mut s, _) = record_with(config, frames, |_| false);
        s.stop(1_000 + (frames + 1) * DT, pose(frames + 1)).unwrap();
        let starts = s.subtrajectories().iter().map(|x| x.start_ns).collect();
        (s, starts)
    }

    fn results_json(header: &str, key: &str, starts: &[i64], errors: &[f64]) -> String {
        let windows: Vec<String> = starts
            .iter()
            .zip(errors)
            .map(|(t, e)| format!(r#"{{"start":{t},"{key}":{e}}}"#))
            .collect();
        format!(r#"{{{header}"windows":[{}]}}"#, windows.join(","))
    }

    #[test]
    fn angle_deg_results_use_the_degree_thresholds() {
        let (mut s, starts) = stopped(r#"{"pose_relation":"angle_deg"}"#, 40);
        let json = results_json(
            r#""window_frames":10,"pose_relation":"angle_deg","unit":"deg","#,
            "error_deg",
            &starts,
            &[1.9, 2.0, 3.9, 4.0],
        );
        s.load_results(&json).unwrap();
        // Medium from 2°, high from 4° (in metres all four would be high).
        assert_eq!(
            (0..4).map(|k| s.subtrajectory_class(k)).collect::<Vec<_>>(),
            [
                ErrorClass::Low,
                ErrorClass::Medium,
                ErrorClass::Medium,
                ErrorClass::High
            ]
        );
        assert_eq!(s.error_at(starts[3]), (ErrorClass::High, Some(4.0)));
        // Markers search 4°, then 2° (thresholds_deg): sub 3, then subs 1 and 2; with the
        // metric list all four would pass 0.10 and subs 0, 1, 2 would be taken.
        let markers = s.markers().unwrap();
        assert_eq!(
            markers
                .iter()
                .map(|m| (m.subtrajectory, m.class))
                .collect::<Vec<_>>(),
            [
                (3, ErrorClass::High),
                (1, ErrorClass::Medium),
                (2, ErrorClass::Medium)
            ]
        );
        // Mean 2.95° is below the unreliable 8°; 0.20 m would have flagged it.
        assert!(!s.results_unreliable());
        let loud = results_json(r#""unit":"deg","#, "error_deg", &starts, &[9.0; 4]);
        s.load_results(&loud).unwrap();
        assert!(s.results_unreliable());
    }

    /// Calibrated results for `starts`: per window `(error, Some((lower, upper)))` or no
    /// interval.
    fn calibrated_json(starts: &[i64], windows: &[(f64, Option<(f64, f64)>)]) -> String {
        let windows: Vec<String> = starts
            .iter()
            .zip(windows)
            .map(|(t, (e, bounds))| match bounds {
                Some((l, u)) => format!(
                    r#"{{"start":{t},"class":"low","error_m":{e},"lower_m":{l},"pairs":3,"raw_m":0.001,"spread_m":0.001,"upper_m":{u}}}"#
                ),
                None => format!(r#"{{"start":{t},"error_m":{e}}}"#),
            })
            .collect();
        format!(
            r#"{{"version":1,"window_frames":10,"pose_relation":"trans_part","unit":"m","calibration":"pixel7-arcore","windows":[{}]}}"#,
            windows.join(",")
        )
    }

    #[test]
    fn classify_by_upper_colours_and_places_markers_by_the_upper_bound() {
        // Errors 3, 4, 12 and 0.5 cm; upper bounds 6, (none), 20 and 15 cm.
        let windows = [
            (0.03, Some((0.01, 0.06))),
            (0.04, None),
            (0.12, Some((0.08, 0.2))),
            (0.005, Some((0.001, 0.15))),
        ];
        let classes = |s: &Session| (0..4).map(|k| s.subtrajectory_class(k)).collect::<Vec<_>>();
        let placed = |s: &Session| {
            s.markers()
                .unwrap()
                .iter()
                .map(|m| (m.subtrajectory, m.class, m.error_m))
                .collect::<Vec<_>>()
        };
        let (mut estimate, starts) = stopped("{}", 40);
        estimate
            .load_results(&calibrated_json(&starts, &windows))
            .unwrap();
        let (mut upper, _) = stopped(r#"{"classify_by":"upper"}"#, 40);
        upper
            .load_results(&calibrated_json(&starts, &windows))
            .unwrap();
        use ErrorClass::{High, Low, Medium};
        // By the estimate (the default): 10 cm finds sub 2; 2 cm subs 0 and 1.
        assert_eq!(classes(&estimate), [Low, Low, High, Low]);
        assert_eq!(
            placed(&estimate),
            [(2, High, 0.12), (0, Medium, 0.03), (1, Medium, 0.04)]
        );
        // By the upper bound: sub 1 has none and keeps its error; 10 cm finds subs 2 and 3,
        // 5 cm sub 0. The markers' errors stay the windows' errors.
        assert_eq!(classes(&upper), [Medium, Low, High, High]);
        assert_eq!(
            placed(&upper),
            [(2, High, 0.12), (3, High, 0.005), (0, Medium, 0.03)]
        );
        // The lookup gives the error and the interval either way.
        assert_eq!(upper.error_at(starts[3]), (High, Some(0.005)));
        assert_eq!(estimate.error_at(starts[3]), (Low, Some(0.005)));
        let w = upper.result_at(starts[3] + 3).unwrap();
        assert_eq!(
            (w.raw, w.interval),
            (
                Some(0.001),
                Some(crate::ErrorInterval {
                    lower: 0.001,
                    upper: 0.15
                })
            )
        );
        assert_eq!(upper.subtrajectory_window(1).unwrap().interval, None);
        assert_eq!(upper.result_at(starts[3] + DT), None);
        assert_eq!(
            upper.results().unwrap().calibration.as_deref(),
            Some("pixel7-arcore")
        );
        // Uncalibrated results: both choices give the same classes.
        let plain = "start,error\n".to_owned()
            + &starts
                .iter()
                .zip(&windows)
                .map(|(t, (e, _))| format!("{t},{e}\n"))
                .collect::<String>();
        upper.load_results(&plain).unwrap();
        assert_eq!(classes(&upper), [Low, Low, High, Low]);
        assert_eq!(upper.subtrajectory_window(3).unwrap().interval, None);
        // The render plan's items take their colour from these classes (the bindings' plan).
        upper
            .load_results(&calibrated_json(&starts, &windows))
            .unwrap();
        let plan = upper.render_plan();
        let frustum_classes: Vec<_> = plan
            .frustums
            .iter()
            .map(|f| upper.subtrajectory_class(f.subtrajectory))
            .collect();
        assert!(!frustum_classes.is_empty());
        for (f, c) in plan.frustums.iter().zip(frustum_classes) {
            assert_eq!(c, classes(&upper)[f.subtrajectory as usize]);
        }
    }

    #[test]
    fn results_that_do_not_fit_the_session_are_refused_naming_both_values() {
        let (mut s, starts) = stopped(r#"{"subtrajectory_frames":20}"#, 40);
        let good = results_json(r#""window_frames":20,"#, "error_m", &starts, &[0.01, 0.2]);
        s.load_results(&good).unwrap();
        let cases = [
            (
                results_json(r#""window_frames":10,"#, "error_m", &starts, &[0.3, 0.3]),
                ["window_frames 10", "subtrajectory_frames 20"],
            ),
            (
                results_json(
                    r#""window_frames":20,"pose_relation":"angle_deg","#,
                    "error_deg",
                    &starts,
                    &[0.3, 0.3],
                ),
                ["pose_relation angle_deg", "pose_relation trans_part"],
            ),
        ];
        for (text, needles) in cases {
            let err = s.load_results(&text).unwrap_err();
            let message = err.to_string();
            assert!(
                matches!(
                    err,
                    Error::InvalidArgument {
                        name: "results",
                        ..
                    }
                ),
                "{err:?}"
            );
            for needle in needles {
                assert!(message.contains(needle), "{message:?} lacks {needle:?}");
            }
            // The earlier results stay.
            assert_eq!(s.subtrajectory_errors(), vec![Some(0.01), Some(0.2)]);
        }
        // Legacy CSV has no window length: it is taken as it is (but it is metres).
        s.load_results(&format!("start,error\n{},0.05\n", starts[0]))
            .unwrap();
        let (mut deg, starts) = stopped(r#"{"pose_relation":"angle_deg"}"#, 20);
        let err = deg
            .load_results(&format!("start,error\n{},0.05\n", starts[0]))
            .unwrap_err();
        assert!(
            err.to_string().contains("pose_relation trans_part"),
            "{err}"
        );
    }

    #[test]
    fn anchors_venue_cells_and_guide() {
        use crate::venue::{CellKind, Tracking};
        let image = |x: f64| Pose::new(DVec3::new(x, 1.0, 3.0), DQuat::from_rotation_x(1.2));
        let mut s = Session::new(SessionConfig::default());
        assert!(matches!(
            s.anchor(0, "lobby-a", image(0.0), Tracking::Full),
            Err(Error::InvalidState(_))
        ));
        s.start(1_000, pose(0)).unwrap();
        for (id, name) in [("", "anchor_id"), ("a,b", "anchor_id")] {
            assert!(matches!(s.anchor(1, id, image(0.0), Tracking::Full),
                Err(Error::InvalidArgument { name: n, .. }) if n == name));
        }
        let nan = Pose::new(DVec3::new(f64::NAN, 0.0, 0.0), DQuat::IDENTITY);
        assert!(matches!(
            s.anchor(1, "lobby-a", nan, Tracking::Full),
            Err(Error::InvalidArgument { name: "pose", .. })
        ));
        assert!(matches!(s.venue_cells(), Err(Error::InvalidState(_))));
        let arcore_map = crate::venue::tests::MAP.replace("\"unity\"", "\"arcore\"");
        assert!(matches!(
            s.load_venue(&arcore_map),
            Err(Error::InvalidArgument {
                name: "map_json",
                ..
            })
        ));
        s.load_venue(crate::venue::tests::MAP).unwrap();
        // Not seen yet, then seen with limited tracking only: not aligned.
        assert!(matches!(s.venue_cells(), Err(Error::InvalidState(_))));
        s.anchor(2, "lobby-a", image(5.0), Tracking::Limited)
            .unwrap();
        assert!(matches!(s.venue_cells(), Err(Error::InvalidState(_))));
        assert!(
            s.alignment()
                .unwrap()
                .as_ref()
                .unwrap_err()
                .reason
                .contains("full")
        );
        s.anchor(3, "lobby-a", image(0.0), Tracking::Full).unwrap();
        let cells = s.venue_cells().unwrap();
        assert!((cells[0].position - DVec3::new(1.0, 1.0, 5.0)).length() < 1e-12);
        // A second full observation refines it: the median of the two.
        s.anchor(4, "lobby-a", image(0.02), Tracking::Full).unwrap();
        let cells = s.venue_cells().unwrap().to_vec();
        assert!((cells[0].position - DVec3::new(1.01, 1.0, 5.0)).length() < 1e-12);
        assert_eq!(cells[1].kind, CellKind::Surface);

        // Guide targets: the markers, then the high surface cell.
        let wall = vec![2000u16; 256 * 192];
        let depth = DepthImage::new(&wall, 256, 192, 512).unwrap();
        let k = Intrinsics {
            cx: 128.0,
            cy: 96.0,
            ..phone_k()
        };
        for i in 1..=60 {
            if s.frame(1_000 + i * DT, pose(i)).unwrap().is_midpoint() {
                s.depth(&depth, &k, DisplayRotation::Deg0).unwrap();
            }
        }
        s.stop(1_000 + 61 * DT, pose(61)).unwrap();
        let starts: Vec<i64> = s.subtrajectories().iter().map(|x| x.start_ns).collect();
        let csv: String = std::iter::once("start,error\n".to_owned())
            .chain(
                starts
                    .iter()
                    .zip([0.12, 0.03, 0.3, 0.11, 0.02, 0.06])
                    .map(|(t, e)| format!("{t},{e}\n")),
            )
            .collect();
        s.load_results(&csv).unwrap();
        let markers = s.markers().unwrap();
        let targets: Vec<DVec3> = s.guide_targets().collect();
        let mut expected: Vec<DVec3> = markers.iter().map(|m| m.position).collect();
        expected.push(cells[1].position);
        assert_eq!(targets, expected);
        let view = ScreenView::new(pose(0), Convention::Unity, 60.0, 1080, 1920, 40.0).unwrap();
        let mut out = vec![Guide::default(); targets.len() - 1];
        assert_eq!(s.guide_into(&view, &mut out), targets.len());
        assert!(
            out.iter().all(|g| *g == Guide::default()),
            "nothing written when too small"
        );
        out.push(Guide::default());
        assert_eq!(s.guide_into(&view, &mut out), targets.len());
        assert_eq!(out[0], view.guide(targets[0]));
        assert_eq!(out[targets.len() - 1], view.guide(cells[1].position));

        assert!(matches!(
            s.anchor(9, "lobby-a", image(0.0), Tracking::Full),
            Err(Error::InvalidState(_))
        ));
        let dir = tempfile::tempdir().unwrap();
        s.save(dir.path()).unwrap();
        let text = std::fs::read_to_string(dir.path().join("anchors.csv")).unwrap();
        assert_eq!(text.lines().count(), 4);
        let loaded = Session::load(dir.path()).unwrap();
        assert_eq!(loaded.anchors(), s.anchors());
        assert_eq!(loaded.markers().unwrap(), markers);
    }

    #[test]
    fn the_alignment_follows_the_observations_within_a_32nd() {
        use crate::venue::Tracking;
        let mut s = Session::new(SessionConfig::default());
        s.start(0, pose(0)).unwrap();
        s.load_venue(crate::venue::tests::MAP).unwrap();
        for i in 1..=2_000i64 {
            let x = 0.001 * (i % 7) as f64;
            let image = Pose::new(DVec3::new(x, 1.0, 3.0), DQuat::IDENTITY);
            s.anchor(i, "lobby-a", image, Tracking::Full).unwrap();
            let a = s.alignment().unwrap().as_ref().unwrap();
            let used = (a.observations + a.rejected) as i64;
            assert!(used * 33 >= i * 32 && used <= i, "{used} of {i}");
            if i <= 32 {
                assert_eq!(used, i, "every one of the first 32 realigns");
            }
        }
    }

    #[test]
    fn markers_render_plan_and_tum() {
        let (mut s, _) = record(60, |k| k == 2);
        s.stop(1_000 + 61 * DT, pose(61)).unwrap();
        let starts: Vec<i64> = s.subtrajectories().iter().map(|x| x.start_ns).collect();
        // Sub 2 (no depth) has the worst error but cannot get a marker.
        let errors = [0.12, 0.03, 0.3, 0.11, 0.02, 0.06];
        let csv: String = std::iter::once("start,error\n".to_owned())
            .chain(starts.iter().zip(errors).map(|(t, e)| format!("{t},{e}\n")))
            .collect();
        s.load_results(&csv).unwrap();
        let m = s.markers().unwrap();
        // Points at x = 0.5 + 1.0·k: 0 (0.12), 3 (0.11) at ≥10 cm; 5 (0.06) at ≥5 cm.
        assert_eq!(
            m.iter().map(|m| m.subtrajectory).collect::<Vec<_>>(),
            vec![0, 3, 5]
        );
        assert_eq!(
            m.iter().map(|m| m.class).collect::<Vec<_>>(),
            vec![ErrorClass::High, ErrorClass::High, ErrorClass::Medium]
        );
        assert!((m[0].normal - DVec3::NEG_Z).length() < 1e-9); // Unity wall ahead faces −Z
        let plan = s.render_plan();
        assert_eq!(plan.joints.len(), 13);
        assert_eq!(plan.segments.len(), 12);
        assert_eq!(plan.stop, Some(pose(61)));
        // 0.1 m per frame: first midpoint at or after 0.5 m of path is frame 5 (sub 0), then
        // one per sub-trajectory (1 m apart).
        assert_eq!(
            plan.frustums
                .iter()
                .map(|f| f.subtrajectory)
                .collect::<Vec<_>>(),
            vec![0, 1, 2, 3, 4, 5]
        );
        let tum = s.trajectory_tum();
        assert_eq!(tum.lines().count(), 13);
        assert!(tum.starts_with("1000 0 1.5 0 0 0 0 1\n"), "{tum}");
    }

    #[test]
    fn extreme_timestamps_are_errors_not_overflows() {
        let mut s = Session::new(SessionConfig::default());
        s.start(i64::MIN, Pose::IDENTITY).unwrap();
        assert!(matches!(
            s.frame(i64::MAX, Pose::IDENTITY),
            Err(Error::InvalidArgument { name: "t_ns", .. })
        ));
        s.frame(-1, Pose::IDENTITY).unwrap();
        s.frame(i64::MAX - 1, Pose::IDENTITY).unwrap();
        let summary = s.stop(i64::MAX, Pose::IDENTITY).unwrap();
        assert_eq!(
            summary.duration_s,
            (i128::from(i64::MAX) - i128::from(i64::MIN)) as f64 / 1e9
        );
        // Intervals i64::MAX - 1 - (i64::MIN + 1) overflow no sum: median of two.
        assert_eq!(
            s.lookup_tolerance_ns(),
            ((i128::from(i64::MAX - 1 - (-1)) + i128::from(-1 - i64::MIN)) / 4) as i64
        );
    }

    #[test]
    fn far_apart_positions_are_errors_not_an_infinite_path() {
        // Found by fuzzing (fuzz target `session`): a start at x = −5.3e304 and a frame at
        // x = −25.6 (finite, valid poses) made the path length infinite; `save` wrote it as
        // `null` and `load` then refused session.json.
        let mut s = Session::new(SessionConfig::default());
        let far = Pose::new(DVec3::new(-5.3e304, 0.0, 0.0), DQuat::IDENTITY);
        s.start(-7_668_058_320_836_127_339, far).unwrap();
        let err = s.frame(16_777_215, pose(-256)).unwrap_err();
        assert!(
            matches!(&err, Error::InvalidArgument { name: "pose", reason } if reason.contains("path length overflows")),
            "{err}"
        );
        s.frame(16_777_215, far).unwrap(); // the rejected frame did not count
        assert!(matches!(
            s.stop(16_777_216, pose(-256)),
            Err(Error::InvalidArgument { name: "pose", .. })
        ));
        let summary = s.stop(16_777_216, far).unwrap();
        assert_eq!((summary.frames, summary.length_m), (1, 0.0));
        let dir = tempfile::tempdir().unwrap();
        s.save(dir.path()).unwrap();
        assert_eq!(Session::load(dir.path()).unwrap(), s);
    }

    #[test]
    fn frame_does_not_reallocate_within_the_reserve() {
        let mut s = Session::new(SessionConfig::default());
        s.start(0, pose(0)).unwrap();
        let caps = (
            s.frame_intervals_ns.capacity(),
            s.logged.capacity(),
            s.subs.capacity(),
        );
        for i in 1..=RESERVE_FRAMES as i64 {
            s.frame(i * DT, pose(i)).unwrap();
        }
        assert_eq!(
            caps,
            (
                s.frame_intervals_ns.capacity(),
                s.logged.capacity(),
                s.subs.capacity()
            )
        );
    }

    #[derive(Debug, Clone)]
    enum Op {
        Start(i64, f64),
        Frame(i64, f64),
        Depth(u16, u32, u32, i32),
        Stop(i64, f64),
        Results(String),
        Query,
    }

    fn arb_op() -> impl proptest::strategy::Strategy<Value = Op> {
        use proptest::prelude::*;
        let x = prop_oneof![4 => -10.0f64..10.0, 1 => Just(f64::NAN), 1 => Just(f64::INFINITY)];
        prop_oneof![
            1 => (0i64..100, x.clone()).prop_map(|(t, x)| Op::Start(t, x)),
            12 => (-5i64..60, x.clone()).prop_map(|(dt, x)| Op::Frame(dt, x)),
            3 => (0u16..3000, 0u32..300, 0u32..300, -1i32..5).prop_map(|(d, w, h, r)| Op::Depth(d, w, h, r)),
            1 => (-5i64..60, x).prop_map(|(dt, x)| Op::Stop(dt, x)),
            1 => ".{0,40}".prop_map(Op::Results),
            1 => (0i64..2000, 0.0f64..0.3).prop_map(|(t, e)| Op::Results(format!("start,error\n{t},{e}\n"))),
            1 => Just(Op::Query),
        ]
    }

    proptest::proptest! {
        /// Any call sequence, including NaN poses, bad images and garbage results: no
        /// panic, and the bookkeeping invariants hold.
        #[test]
        fn random_call_sequences_never_panic(ops in proptest::collection::vec(arb_op(), 0..120)) {
            let mut s = Session::new(SessionConfig { subtrajectory_frames: 4, ..SessionConfig::default() });
            let mut t = 0i64;
            let k = phone_k();
            for op in ops {
                match op {
                    Op::Start(t0, x) => { t = t0; let _ = s.start(t0, Pose::new(DVec3::new(x, 0.0, 0.0), DQuat::IDENTITY)); }
                    Op::Frame(dt, x) => { t += dt; let _ = s.frame(t, Pose::new(DVec3::new(x, 1.0, 0.0), DQuat::IDENTITY)); }
                    Op::Depth(d, w, h, r) => {
                        let data = vec![d; (w * h) as usize];
                        if let (Ok(img), Ok(rot)) = (DepthImage::new(&data, w, h, 2 * w), DisplayRotation::from_degrees(r * 90)) {
                            let _ = s.depth(&img, &k, rot);
                        }
                    }
                    Op::Stop(dt, x) => { t += dt; let _ = s.stop(t, Pose::new(DVec3::new(x, 0.0, 0.0), DQuat::IDENTITY)); }
                    Op::Results(text) => { let _ = s.load_results(&text); }
                    Op::Query => {
                        let _ = s.markers();
                        let _ = s.render_plan();
                        let _ = s.error_at(t);
                        let _ = s.results_unreliable();
                        let _ = s.trajectory_tum();
                    }
                }
                for (i, sub) in s.subtrajectories().iter().enumerate() {
                    proptest::prop_assert_eq!(sub.index as usize, i);
                }
                // Start, every midpoint, every endpoint.
                let completed = s.subtrajectories().iter().filter(|x| x.end_ns.is_some()).count();
                let started = usize::from(s.state() != SessionState::Idle);
                proptest::prop_assert_eq!(s.logged().len(), started * (1 + s.subtrajectories().len() + completed));
                if let Some(sum) = s.summary() {
                    proptest::prop_assert!(sum.depth_samples <= sum.midpoints && sum.subtrajectories <= sum.midpoints);
                    proptest::prop_assert_eq!(sum.midpoints, sum.frames / 4 + u32::from(sum.frames % 4 >= 2));
                }
            }
        }

        #[test]
        fn parsers_never_panic(text in "\\PC{0,80}") {
            let _ = Results::parse(&text);
            let _ = Results::parse(&format!("{{\"windows\":[{text}]}}"));
            let _ = SessionConfig::from_json(&text);
            let _ = SessionConfig::from_json(&format!("{{\"thresholds_m\":{text}}}"));
            let _ = crate::tum::parse_tum_ns(&text, "t");
        }
    }
}
