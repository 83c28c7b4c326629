//! The one safe API of the library. The C ABI and JNI entry points are generated around
//! these functions from their declarations in `exports.rs`.

use std::ffi::CStr;
use std::path::{Path, PathBuf};
use std::sync::{LazyLock, Mutex};

use sitar_core::{
    DepthImage, DisplayRotation, LumaImage, PlaybackLogger, ScreenView, Session, SessionConfig,
    Tracking,
};

use sitar_client::UploadJob;
use sitar_core::calibration::{Target, SOURCE_REPLAYS, SOURCE_WALK};

pub(crate) use crate::android_tls::platform_tls_init;
use crate::error::{lock, Error};
use crate::registry::{Registry, SitarHandle};
use crate::types::{
    SitarEvidence, SitarFrustum, SitarGuide, SitarIntrinsics, SitarJobProgress, SitarJoint,
    SitarMarker, SitarPose, SitarSegment, SitarSubtrajectoryResult, SitarSummary, SitarVenueCell,
};

static SESSIONS: LazyLock<Registry<Mutex<Session>>> = LazyLock::new(|| Registry::new("session"));
static PLAYBACKS: LazyLock<Registry<Mutex<PlaybackLogger>>> =
    LazyLock::new(|| Registry::new("playback"));
static UPLOADS: LazyLock<Registry<UploadJob>> = LazyLock::new(|| Registry::new("upload"));

/// The render plan as flat C structs, each item tagged with its class.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RenderPlanC {
    /// Path segments.
    pub segments: Vec<SitarSegment>,
    /// Spheres between segments.
    pub joints: Vec<SitarJoint>,
    /// Camera frustums.
    pub frustums: Vec<SitarFrustum>,
    /// Start and stop poses, if recorded.
    pub ends: PlanEnds,
}

/// The start and stop poses of a render plan.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PlanEnds {
    /// Start pose, if recorded.
    pub start: Option<SitarPose>,
    /// Stop pose, if recorded.
    pub stop: Option<SitarPose>,
}

/// The class and error at a timestamp.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SitarErrorAt {
    /// 0 unknown, 1 low, 2 medium, 3 high.
    pub error_class: i32,
    /// The error in the results' unit (metres; degrees for `angle_deg`); NaN when unknown.
    pub error_m: f64,
}

/// The interval of the result window at a timestamp (calibrated results).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SitarBoundsAt {
    /// 1 when the window found has an interval; 0 when no window is within the tolerance,
    /// no results are loaded, or the results are not calibrated.
    pub present: i32,
    /// Lower bound in the results' unit (metres; degrees for `angle_deg`); NaN when absent.
    pub lower_m: f64,
    /// Upper bound in the results' unit; NaN when absent.
    pub upper_m: f64,
    /// The window's uncalibrated estimate in the results' unit; NaN when absent (no window,
    /// uncalibrated results, or `null` in the results).
    pub raw_m: f64,
}

/// Where the loaded results come from (`"source"`, `"target"`, `"runs"`, `"informative"`),
/// as codes: 0 is always "not said" (no results loaded, or results that do not say, such as
/// legacy CSV).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SitarProvenance {
    /// 0 not said, 1 the walk itself (estimated on the phone at stop, or by the backend at
    /// upload), 2 replays.
    pub source: i32,
    /// 0 not said, 1 the error of the live run (the user's own walk), 2 the expected error
    /// at each place.
    pub target: i32,
    /// Runs the results come from (the walk and its replays); 0 not said.
    pub runs: u32,
    /// 1 the calibration's runs predict the error, 0 they do not (the colours are a guess),
    /// -1 not said.
    pub informative: i32,
}

/// A depth image borrowed from the caller: 16-bit millimetres, any row stride.
#[derive(Debug, Clone, Copy)]
pub struct DepthView<'a> {
    data: &'a [u16],
    width: u32,
    height: u32,
    row_stride_bytes: u32,
}

impl<'a> DepthView<'a> {
    /// Checks the geometry (positive size, even stride ≥ 2·width) and that `data` holds
    /// the image.
    pub fn new(
        data: &'a [u16],
        width: i32,
        height: i32,
        row_stride_bytes: i32,
    ) -> Result<Self, Error> {
        let needed = depth_len(width, height, row_stride_bytes)?;
        if data.len() < needed {
            return Err(Error::invalid(
                "depth_mm",
                format!(
                    "{} samples; a {width}x{height} image with row stride {row_stride_bytes} bytes needs {needed}",
                    data.len()
                ),
            ));
        }
        // depth_len checked that all three are positive.
        Ok(DepthView {
            data: &data[..needed],
            width: width as u32,
            height: height as u32,
            row_stride_bytes: row_stride_bytes as u32,
        })
    }
}

/// The library version (`CARGO_PKG_VERSION`), NUL-terminated; never fails (a `Result` like
/// every export).
pub fn version() -> Result<&'static CStr, Error> {
    const VERSION: &CStr =
        match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
            Ok(v) => v,
            Err(_) => panic!("the crate version contains a NUL byte"),
        };
    Ok(VERSION)
}

fn with_session<R>(
    h: SitarHandle,
    f: impl FnOnce(&mut Session) -> Result<R, Error>,
) -> Result<R, Error> {
    // The registry's read lock is held for the call (no Arc clone on the
    // frame path); nothing in `f` touches the session registry.
    SESSIONS.with(h, |shared| f(&mut *lock(shared)?))?
}

/// Creates a session from its JSON config ("" or "{}" = defaults).
pub fn session_new(config_json: &str) -> Result<SitarHandle, Error> {
    crate::logging::init();
    let config = SessionConfig::from_json(config_json)?;
    let h = SESSIONS.insert(Mutex::new(Session::new(config)));
    log::info!("session {h:#x} created");
    Ok(h)
}

/// Frees a session; the handle is invalid afterwards. A running upload keeps
/// its own reference and finishes or can be cancelled.
pub fn session_free(h: SitarHandle) -> Result<(), Error> {
    SESSIONS.remove(h).map(drop)
}

/// Starts recording (frame 0).
pub fn session_start(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> Result<(), Error> {
    let pose = pose.to_core();
    with_session(h, |s| Ok(s.start(t_ns, pose)?))
}

/// One camera frame; returns flags (1 = midpoint: give depth, 2 = endpoint).
pub fn session_frame(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> Result<u32, Error> {
    let pose = pose.to_core();
    with_session(h, |s| Ok(s.frame(t_ns, pose)?.0))
}

/// The depth image for the last midpoint.
pub fn session_depth(
    h: SitarHandle,
    image: DepthView<'_>,
    k: &SitarIntrinsics,
    display_rotation_deg: i32,
) -> Result<(), Error> {
    let image = DepthImage::new(
        image.data,
        image.width,
        image.height,
        image.row_stride_bytes,
    )?;
    let rotation = DisplayRotation::from_degrees(display_rotation_deg)?;
    let k = k.to_core();
    with_session(h, |s| Ok(s.depth(&image, &k, rotation)?))
}

/// A camera luminance plane borrowed from the caller: 8-bit, any row stride.
#[derive(Debug, Clone, Copy)]
pub struct LumaView<'a> {
    data: &'a [u8],
    width: u32,
    height: u32,
    row_stride_bytes: u32,
}

impl<'a> LumaView<'a> {
    /// Checks the geometry (positive size, stride ≥ width) and that `data` holds the plane.
    pub fn new(
        data: &'a [u8],
        width: i32,
        height: i32,
        row_stride_bytes: i32,
    ) -> Result<Self, Error> {
        let needed = luma_len(width, height, row_stride_bytes)?;
        if data.len() < needed {
            return Err(Error::invalid(
                "luma",
                format!(
                    "{} bytes; a {width}x{height} plane with row stride {row_stride_bytes} needs {needed}",
                    data.len()
                ),
            ));
        }
        // luma_len checked that all three are positive.
        Ok(LumaView {
            data: &data[..needed],
            width: width as u32,
            height: height as u32,
            row_stride_bytes: row_stride_bytes as u32,
        })
    }
}

/// Number of bytes a luminance plane of this geometry occupies (the last row unpadded).
pub fn luma_len(width: i32, height: i32, row_stride_bytes: i32) -> Result<usize, Error> {
    if width <= 0 || height <= 0 {
        return Err(Error::invalid(
            "width/height",
            format!("luma plane is {width}x{height}; both must be positive"),
        ));
    }
    if row_stride_bytes < width {
        return Err(Error::invalid(
            "row_stride_bytes",
            format!("{row_stride_bytes} is less than the width {width}"),
        ));
    }
    Ok((height as usize - 1) * row_stride_bytes as usize + width as usize)
}

/// The camera image (luminance plane, sensor orientation) for the latest midpoint.
pub fn session_image(
    h: SitarHandle,
    image: LumaView<'_>,
    display_rotation_deg: i32,
) -> Result<(), Error> {
    let rotation = DisplayRotation::from_degrees(display_rotation_deg)?;
    let image = LumaImage::new(
        image.data,
        image.width,
        image.height,
        image.row_stride_bytes,
    )?;
    with_session(h, |s| Ok(s.image(&image, rotation)?))
}

/// Properties and likely causes of sub-trajectory `k`.
pub fn session_subtrajectory_evidence(h: SitarHandle, k: u32) -> Result<SitarEvidence, Error> {
    with_session(h, |s| {
        let evidence = s.evidence_of(k)?;
        let size = s
            .midpoint_inputs()
            .get(k as usize)
            .map_or((0, 0), |i| i.thumbnail_size);
        Ok(SitarEvidence::new(&evidence, size))
    })
}

/// The JPEG thumbnail of sub-trajectory `k` (empty without an image).
pub fn session_thumbnail(h: SitarHandle, k: u32) -> Result<Vec<u8>, Error> {
    with_session(h, |s| {
        let n = s.subtrajectories().len();
        if k as usize >= n {
            return Err(Error::invalid(
                "k",
                format!("{k} is not a sub-trajectory (there are {n})"),
            ));
        }
        Ok(s.thumbnail(k).map(<[u8]>::to_vec).unwrap_or_default())
    })
}

/// Number of `u16` elements a depth image of this geometry occupies.
pub fn depth_len(width: i32, height: i32, row_stride_bytes: i32) -> Result<usize, Error> {
    if width <= 0 || height <= 0 {
        return Err(Error::invalid(
            "width/height",
            format!("depth image is {width}x{height}; both must be positive"),
        ));
    }
    if row_stride_bytes % 2 != 0 {
        return Err(Error::invalid(
            "row_stride_bytes",
            format!("{row_stride_bytes} is odd; rows of 16-bit samples need an even stride"),
        ));
    }
    if row_stride_bytes < width.saturating_mul(2) {
        return Err(Error::invalid(
            "row_stride_bytes",
            format!(
                "{row_stride_bytes} is less than width*2 = {}",
                i64::from(width) * 2
            ),
        ));
    }
    let bytes = (height as usize - 1) * row_stride_bytes as usize + width as usize * 2;
    Ok(bytes / 2)
}

/// Stops recording and returns the summary.
pub fn session_stop(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> Result<SitarSummary, Error> {
    let _trace = crate::trace::section("sitar stop");
    let pose = pose.to_core();
    with_session(h, |s| Ok(SitarSummary::from(&s.stop(t_ns, pose)?)))
}

/// The summary of a stopped recording.
pub fn session_summary(h: SitarHandle) -> Result<SitarSummary, Error> {
    with_session(h, |s| {
        s.summary()
            .map(|sum| SitarSummary::from(&sum))
            .ok_or_else(|| Error::InvalidState("no summary: the recording is not stopped".into()))
    })
}

/// Loads results (legacy CSV or JSON) into the session.
pub fn session_load_results(h: SitarHandle, csv_or_json: &str) -> Result<(), Error> {
    let _trace = crate::trace::section("sitar load results");
    with_session(h, |s| Ok(s.load_results(csv_or_json)?))
}

/// Class (0 unknown … 3 high) and error (NaN when unknown) at a timestamp.
pub fn session_error_at(h: SitarHandle, t_ns: i64) -> Result<SitarErrorAt, Error> {
    with_session(h, |s| {
        let (class, error) = s.error_at(t_ns);
        Ok(SitarErrorAt {
            error_class: class as i32,
            error_m: error.unwrap_or(f64::NAN),
        })
    })
}

/// The interval (and raw value) of the window `session_error_at` finds at a timestamp.
pub fn session_bounds_at(h: SitarHandle, t_ns: i64) -> Result<SitarBoundsAt, Error> {
    with_session(h, |s| {
        let window = s.result_at(t_ns);
        let interval = window.and_then(|w| w.interval);
        Ok(SitarBoundsAt {
            present: i32::from(interval.is_some()),
            lower_m: interval.map_or(f64::NAN, |i| i.lower),
            upper_m: interval.map_or(f64::NAN, |i| i.upper),
            raw_m: window.and_then(|w| w.raw).unwrap_or(f64::NAN),
        })
    })
}

/// The name of the calibration of the loaded results; "" when uncalibrated or none loaded.
pub fn session_results_calibration(h: SitarHandle) -> Result<String, Error> {
    with_session(h, |s| {
        Ok(s.results()
            .and_then(|r| r.calibration.clone())
            .unwrap_or_default())
    })
}

/// Takes a calibration (the JSON file `sitar calibrate` writes) for the estimate from the
/// walk: at `stop` (or at once, when already stopped without the backend's results) the
/// sub-trajectories get the calibrated error of the walk alone, offline.
pub fn session_set_calibration(h: SitarHandle, json: &str) -> Result<(), Error> {
    let _trace = crate::trace::section("sitar set calibration");
    with_session(h, |s| Ok(s.set_calibration(json)?))
}

/// Where the loaded results come from; every field "not said" without results.
pub fn session_results_provenance(h: SitarHandle) -> Result<SitarProvenance, Error> {
    with_session(h, |s| {
        let Some(r) = s.results() else {
            return Ok(SitarProvenance {
                informative: -1,
                ..SitarProvenance::default()
            });
        };
        let code = |value: Option<&str>, one: &str, two: &str| match value {
            Some(v) if v == one => 1,
            Some(v) if v == two => 2,
            _ => 0,
        };
        Ok(SitarProvenance {
            source: code(r.source.as_deref(), SOURCE_WALK, SOURCE_REPLAYS),
            target: code(
                r.target.as_deref(),
                Target::Live.name(),
                Target::Expected.name(),
            ),
            runs: r.runs.unwrap_or(0),
            informative: r.informative.map_or(-1, i32::from),
        })
    })
}

/// The markers (needs results).
pub fn session_markers(h: SitarHandle) -> Result<Vec<SitarMarker>, Error> {
    let _trace = crate::trace::section("sitar markers");
    with_session(h, |s| {
        Ok(s.markers()?.iter().map(SitarMarker::from).collect())
    })
}

/// Whether the loaded results are too noisy to trust.
pub fn session_results_unreliable(h: SitarHandle) -> Result<bool, Error> {
    with_session(h, |s| Ok(s.results_unreliable()))
}

/// The class of sub-trajectory `k`.
pub fn session_subtrajectory_class(h: SitarHandle, k: u32) -> Result<i32, Error> {
    with_session(h, |s| Ok(s.subtrajectory_class(k) as i32))
}

/// Every sub-trajectory's error and class, in order.
pub fn session_subtrajectory_results(
    h: SitarHandle,
) -> Result<Vec<SitarSubtrajectoryResult>, Error> {
    with_session(h, |s| {
        Ok(s.subtrajectory_errors()
            .into_iter()
            .enumerate()
            .map(|(k, e)| SitarSubtrajectoryResult {
                error_m: e.unwrap_or(f64::NAN),
                subtrajectory: k as u32,
                error_class: s.subtrajectory_class(k as u32) as i32,
            })
            .collect())
    })
}

/// The render plan with each item's class.
pub fn session_render_plan(h: SitarHandle) -> Result<RenderPlanC, Error> {
    let _trace = crate::trace::section("sitar render plan");
    with_session(h, |s| {
        let plan = s.render_plan();
        let class = |k: u32| s.subtrajectory_class(k) as i32;
        Ok(RenderPlanC {
            segments: plan
                .segments
                .iter()
                .map(|g| SitarSegment {
                    cx: g.centre.x,
                    cy: g.centre.y,
                    cz: g.centre.z,
                    qx: g.rotation.x,
                    qy: g.rotation.y,
                    qz: g.rotation.z,
                    qw: g.rotation.w,
                    length: g.length,
                    subtrajectory: g.subtrajectory,
                    error_class: class(g.subtrajectory),
                })
                .collect(),
            joints: plan
                .joints
                .iter()
                .map(|j| SitarJoint {
                    px: j.position.x,
                    py: j.position.y,
                    pz: j.position.z,
                    subtrajectory: j.subtrajectory,
                    error_class: class(j.subtrajectory),
                })
                .collect(),
            frustums: plan
                .frustums
                .iter()
                .map(|f| SitarFrustum {
                    pose: SitarPose::from_core(&f.pose),
                    subtrajectory: f.subtrajectory,
                    error_class: class(f.subtrajectory),
                })
                .collect(),
            ends: PlanEnds {
                start: plan.start.as_ref().map(SitarPose::from_core),
                stop: plan.stop.as_ref().map(SitarPose::from_core),
            },
        })
    })
}

/// Render plan: the path segments.
pub fn session_segments(h: SitarHandle) -> Result<Vec<SitarSegment>, Error> {
    Ok(session_render_plan(h)?.segments)
}

/// Render plan: the joints between segments.
pub fn session_joints(h: SitarHandle) -> Result<Vec<SitarJoint>, Error> {
    Ok(session_render_plan(h)?.joints)
}

/// Render plan: the camera frustums.
pub fn session_frustums(h: SitarHandle) -> Result<Vec<SitarFrustum>, Error> {
    Ok(session_render_plan(h)?.frustums)
}

/// Render plan: the start and stop poses.
pub fn session_plan_ends(h: SitarHandle) -> Result<PlanEnds, Error> {
    Ok(session_render_plan(h)?.ends)
}

/// The logged poses as TUM text (integer nanoseconds).
pub fn session_trajectory_tum(h: SitarHandle) -> Result<String, Error> {
    with_session(h, |s| Ok(s.trajectory_tum()))
}

/// Saves the session folder.
pub fn session_save(h: SitarHandle, dir: &Path) -> Result<(), Error> {
    let _trace = crate::trace::section("sitar save");
    with_session(h, |s| Ok(s.save(dir)?))
}

/// Writes the session's scene as a `.glb` file (see `sitar_scene`).
pub fn session_export_gltf(h: SitarHandle, path: &Path) -> Result<(), Error> {
    let _trace = crate::trace::section("sitar export gltf");
    let glb = with_session(h, |s| {
        Ok(sitar_scene::to_glb(
            &sitar_scene::SceneParts::from_session(s),
        )?)
    })?;
    std::fs::write(path, glb).map_err(|source| Error::Io {
        context: format!("cannot write the scene to {}", path.display()),
        source,
    })
}

/// Loads a saved session folder as a new session.
pub fn session_load(dir: &Path) -> Result<SitarHandle, Error> {
    crate::logging::init();
    let _trace = crate::trace::section("sitar load");
    let session = Session::load(dir)?;
    Ok(SESSIONS.insert(Mutex::new(session)))
}

/// Creates a playback logger; only `convention` of the config matters.
pub fn playback_new(config_json: &str) -> Result<SitarHandle, Error> {
    crate::logging::init();
    let config = SessionConfig::from_json(config_json)?;
    Ok(PLAYBACKS.insert(Mutex::new(PlaybackLogger::new(config.convention))))
}

/// Logs one playback frame.
pub fn playback_log(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> Result<(), Error> {
    let pose = pose.to_core();
    let shared = PLAYBACKS.get(h)?;
    let mut p = lock(&shared)?;
    Ok(p.log(t_ns, pose)?)
}

/// Number of poses logged.
pub fn playback_len(h: SitarHandle) -> Result<usize, Error> {
    let shared = PLAYBACKS.get(h)?;
    let p = lock(&shared)?;
    Ok(p.len())
}

/// The logged poses as TUM text.
pub fn playback_tum(h: SitarHandle) -> Result<String, Error> {
    let shared = PLAYBACKS.get(h)?;
    let p = lock(&shared)?;
    Ok(p.to_tum())
}

/// Writes `<dir>/trajectory_<index>.txt` (creating `dir`) and returns the path.
pub fn playback_write(h: SitarHandle, dir: &Path, index: u32) -> Result<PathBuf, Error> {
    let _trace = crate::trace::section("sitar playback write");
    let shared = PLAYBACKS.get(h)?;
    let p = lock(&shared)?;
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        context: format!("cannot create {}", dir.display()),
        source,
    })?;
    let path = dir.join(format!("trajectory_{index}.txt"));
    p.write(&path)?;
    Ok(path)
}

/// Frees a playback logger.
pub fn playback_free(h: SitarHandle) -> Result<(), Error> {
    PLAYBACKS.remove(h).map(drop)
}

/// Starts the background upload of `recording` and download of the results into session
/// `h` (a [`sitar_client::UploadJob`]). `options_json` (`None` or "" = defaults) keys, all
/// optional: `server_url` (else the session config's), `server_token` (the backend's access
/// token, sent as `Authorization: Bearer …`), `server_cert_sha256` (pins the backend's TLS
/// certificate by its SHA-256 fingerprint; a different certificate fails the job with
/// `SITAR_ERR_NETWORK`), `trials` (10), `setting`
/// ("trim_mean_30"), `playback` ("adb"), `poll_interval_ms` (500), `session_id` (continue
/// that server session, e.g. a failed job's: the upload resumes or is skipped),
/// `window_frames` and `pose_relation` (the session config's `subtrajectory_frames` and
/// `pose_relation`; other values are refused, as their results could not be shown).
pub fn upload_start(
    h: SitarHandle,
    recording: &Path,
    options_json: Option<&str>,
) -> Result<SitarHandle, Error> {
    let session = SESSIONS.get(h)?;
    let job = crate::upload::start(session, recording, options_json.unwrap_or(""))?;
    Ok(UPLOADS.insert(job))
}

/// A snapshot of an upload job.
pub fn upload_progress(job: SitarHandle) -> Result<SitarJobProgress, Error> {
    let job = UPLOADS.get(job)?;
    Ok(crate::upload::progress(&job))
}

/// Why the job failed ("" otherwise).
pub fn upload_message(job: SitarHandle) -> Result<String, Error> {
    let job = UPLOADS.get(job)?;
    Ok(crate::upload::message(&job))
}

/// The server's session id ("" until created).
pub fn upload_server_id(job: SitarHandle) -> Result<String, Error> {
    Ok(UPLOADS.get(job)?.server_id().unwrap_or_default())
}

/// Cancels the job: its state becomes cancelled at once and no more results
/// are loaded into the session.
pub fn upload_cancel(job: SitarHandle) -> Result<(), Error> {
    UPLOADS.get(job)?.cancel();
    Ok(())
}

/// Frees a job handle (cancelling it if still running).
pub fn upload_free(job: SitarHandle) -> Result<(), Error> {
    UPLOADS.remove(job)?.cancel();
    Ok(())
}

/// An array output the caller owns (C's `out, capacity, out_len`): [`Fill::write`] sets the
/// count and writes the items only when all of them fit — no allocation.
#[derive(Debug)]
pub struct Fill<'a, T> {
    items: &'a mut [T],
    out_len: &'a mut usize,
}

impl<'a, T> Fill<'a, T> {
    /// Room for `items.len()` items; `*out_len` receives the count.
    pub fn new(items: &'a mut [T], out_len: &'a mut usize) -> Self {
        Self { items, out_len }
    }

    /// `*out_len = n`; when `n` items fit, writes `items` (which yields `n`), else
    /// [`Error::BufferTooSmall`] and nothing written.
    pub fn write(self, n: usize, items: impl Iterator<Item = T>) -> Result<(), Error> {
        *self.out_len = n;
        if n > self.items.len() {
            return Err(Error::BufferTooSmall {
                needed: n,
                capacity: self.items.len(),
            });
        }
        for (slot, item) in self.items.iter_mut().zip(items) {
            *slot = item;
        }
        Ok(())
    }
}

/// Records an observation of anchor image `anchor_id` (1…64 bytes): the pose the platform
/// reports for the tracked image and `tracking` (0 none, 1 limited, 2 full).
pub fn session_anchor(
    h: SitarHandle,
    t_ns: i64,
    anchor_id: &str,
    pose: &SitarPose,
    tracking: i32,
) -> Result<(), Error> {
    let pose = pose.to_core();
    let tracking = Tracking::from_code(tracking)?;
    with_session(h, |s| Ok(s.anchor(t_ns, anchor_id, pose, tracking)?))
}

/// Loads a venue map (`map.json`) and aligns the session to it.
pub fn session_load_venue(h: SitarHandle, map_json: &str) -> Result<(), Error> {
    with_session(h, |s| Ok(s.load_venue(map_json)?))
}

/// The venue's cells in the session's world frame, into the caller's array.
pub fn session_venue_cells(h: SitarHandle, out: Fill<'_, SitarVenueCell>) -> Result<(), Error> {
    with_session(h, |s| {
        let cells = s.venue_cells()?;
        out.write(cells.len(), cells.iter().map(SitarVenueCell::from))
    })
}

/// [`session_venue_cells`] as a list (JNI).
pub fn session_venue_cell_list(h: SitarHandle) -> Result<Vec<SitarVenueCell>, Error> {
    with_session(h, |s| {
        Ok(s.venue_cells()?.iter().map(SitarVenueCell::from).collect())
    })
}

/// The screen of a `guide` call in the session's convention (the arguments checked).
fn screen_view(
    s: &Session,
    camera: &SitarPose,
    vfov_deg: f64,
    width_px: i32,
    height_px: i32,
    margin_px: f64,
) -> Result<ScreenView, Error> {
    let convention = s.config().convention;
    Ok(ScreenView::new(
        camera.to_core(),
        convention,
        vfov_deg,
        width_px,
        height_px,
        margin_px,
    )?)
}

/// Where each marker, then each high venue surface cell, is shown on the screen, into the
/// caller's array.
#[allow(clippy::too_many_arguments)] // the C signature the issue fixes
pub fn session_guide(
    h: SitarHandle,
    camera: &SitarPose,
    vfov_deg: f64,
    width_px: i32,
    height_px: i32,
    margin_px: f64,
    out: Fill<'_, SitarGuide>,
) -> Result<(), Error> {
    with_session(h, |s| {
        let view = screen_view(s, camera, vfov_deg, width_px, height_px, margin_px)?;
        let guides = s.guide_targets().map(|t| SitarGuide::from(view.guide(t)));
        out.write(s.guide_targets().count(), guides)
    })
}

/// [`session_guide`] as a list (JNI).
pub fn session_guide_list(
    h: SitarHandle,
    camera: &SitarPose,
    vfov_deg: f64,
    width_px: i32,
    height_px: i32,
    margin_px: f64,
) -> Result<Vec<SitarGuide>, Error> {
    with_session(h, |s| {
        let view = screen_view(s, camera, vfov_deg, width_px, height_px, margin_px)?;
        Ok(s.guide_targets()
            .map(|t| SitarGuide::from(view.guide(t)))
            .collect())
    })
}

/// Panics on purpose (feature `testing`): proves panics become errors.
#[cfg(feature = "testing")]
pub fn testing_panic() -> Result<(), Error> {
    panic!("sitar_testing_panic: panicking on purpose")
}
