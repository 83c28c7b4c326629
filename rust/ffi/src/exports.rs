//! Every export of `libsitar.so`, declared once (the syntax: [`crate::exports_macro`]). Each
//! line makes the C entry point `sitar_*` (header `include/sitar.h`, C#
//! `NativeMethods.g.cs`) and/or the JNI entry point `Java_io_github_sitar_Native_*`
//! (`Native.kt`) around the safe function of the same name in `bridge.rs`.

// The C functions are called from C and C#, where `unsafe fn` means nothing; each checks
// its pointers for NULL (`c_api.rs`) and documents what else it needs.
#![allow(clippy::not_unsafe_ptr_arg_deref)]

use std::ffi::c_char;

use jni::objects::{JByteArray, JByteBuffer, JClass, JObject, JShortArray, JString};
use jni::sys::{jdouble, jint, jlong};
use jni::EnvUnowned;

use crate::bridge::{PlanEnds, RenderPlanC, SitarBoundsAt, SitarErrorAt, SitarProvenance};
use crate::registry::SitarHandle;
use crate::types::{
    SitarEvidence, SitarFrustum, SitarGuide, SitarIntrinsics, SitarJobProgress, SitarJoint,
    SitarMarker, SitarPose, SitarSegment, SitarSubtrajectoryResult, SitarSummary, SitarVenueCell,
};

crate::exports_macro::exports! {
    /// The library version as a static NUL-terminated string (never freed).
    fn version() -> &'static std::ffi::CStr
        => c sitar_version(static) jni version;

    /// Creates a session from a JSON config (every key optional; "" = defaults).
    fn session_new(config_json: &str) -> SitarHandle
        => c sitar_session_new(out: SitarHandle) jni sessionNew;

    /// Frees a session; any later use of the handle is `SITAR_ERR_INVALID_HANDLE`.
    fn session_free(h: SitarHandle)
        => c sitar_session_free() jni sessionFree;

    /// Starts recording at `t_ns` with `pose` (frame 0).
    fn session_start(h: SitarHandle, t_ns: i64, pose: &SitarPose)
        => c sitar_session_start() jni sessionStart;

    /// One camera frame. `*out_flags`: 1 = midpoint (give depth), 2 = endpoint.
    /// Allocation-free on non-logging frames.
    fn session_frame(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> u32
        => c sitar_session_frame(out_flags: u32) jni sessionFrame;

    /// The depth image (16-bit millimetres, sensor orientation) for the last
    /// midpoint. `depth_mm` must hold `(height-1)*row_stride_bytes + width*2` bytes.
    fn session_depth(h: SitarHandle, depth_mm: DepthPointer, k: &SitarIntrinsics,
        display_rotation: i32)
        => c sitar_session_depth();

    /// The depth image from a direct `ByteBuffer` (ARCore's `Image.planes[0].buffer`).
    fn session_depth(h: SitarHandle, buffer: DirectBuffer, k: &SitarIntrinsics,
        display_rotation: i32)
        => jni sessionDepthBuffer;

    /// The depth image from a `ShortArray` (row stride in bytes).
    fn session_depth(h: SitarHandle, data: ShortArray, k: &SitarIntrinsics,
        display_rotation: i32)
        => jni sessionDepthArray;

    /// The camera's luminance plane (8-bit, sensor orientation; ARCore `Image` plane 0,
    /// AR Foundation `XRCpuImage` Y plane) for the latest midpoint: give it when a frame
    /// returns the midpoint flag (1), with that frame's image. `luma` must hold
    /// `(height-1)*row_stride_bytes + width` bytes. Keeps a display-oriented JPEG thumbnail
    /// and the image properties; a no-op with `"images": false` in the config.
    fn session_image(h: SitarHandle, luma: LumaPointer, display_rotation: i32)
        => c sitar_session_image();

    /// The luminance plane from a direct `ByteBuffer` (ARCore's `Image.planes[0].buffer`).
    fn session_image(h: SitarHandle, luma: LumaBuffer, display_rotation: i32)
        => jni sessionImageBuffer;

    /// The luminance plane from a `ByteArray` (row stride in bytes).
    fn session_image(h: SitarHandle, luma: ByteArray, display_rotation: i32)
        => jni sessionImageArray;

    /// Properties of what the camera saw at sub-trajectory `k`, how it moved, its depth and
    /// the likely causes of its error (`causes` bit set; see `SitarEvidence`).
    fn session_subtrajectory_evidence(h: SitarHandle, k: u32) -> SitarEvidence
        => c sitar_session_subtrajectory_evidence(out: SitarEvidence)
           jni sessionSubtrajectoryEvidence;

    /// The greyscale JPEG thumbnail of sub-trajectory `k` (array-output convention; 0 bytes
    /// without an image).
    fn session_thumbnail(h: SitarHandle, k: u32) -> Vec<u8>
        => c sitar_session_thumbnail(items: u8) jni sessionThumbnail;

    /// Stops recording and writes the summary.
    fn session_stop(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> SitarSummary
        => c sitar_session_stop(out: SitarSummary) jni sessionStop;

    /// The summary of a stopped recording (`SITAR_ERR_INVALID_STATE` before stop).
    fn session_summary(h: SitarHandle) -> SitarSummary
        => c sitar_session_summary(out: SitarSummary) jni sessionSummary;

    /// Loads results: legacy CSV (`start,error`) or JSON, autodetected. Results for
    /// another window length than `subtrajectory_frames`, or another `pose_relation`
    /// than the config's, are refused (`SITAR_ERR_INVALID_ARGUMENT`).
    fn session_load_results(h: SitarHandle, csv_or_json: &str)
        => c sitar_session_load_results() jni sessionLoadResults;

    /// The error class at `t_ns` (0 unknown, 1 low, 2 medium, 3 high) and the
    /// error in the results' unit, metres or degrees (NaN when unknown).
    fn session_error_at(h: SitarHandle, t_ns: i64) -> SitarErrorAt
        => c sitar_session_error_at(out_class: i32, out_error_m: f64) jni sessionErrorAt;

    /// The interval of the result window `sitar_session_error_at` finds at `t_ns`, in the
    /// results' unit (metres, or degrees): the true error lies in [lower, upper] with the
    /// calibration's coverage. `*out_present` = 1 when the window has one, else 0 (no window
    /// within the tolerance, no results, or uncalibrated results) and the bounds are NaN.
    /// `*out_raw_m`: the window's uncalibrated estimate, NaN when absent.
    fn session_bounds_at(h: SitarHandle, t_ns: i64) -> SitarBoundsAt
        => c sitar_session_bounds_at(out_present: i32, out_lower_m: f64, out_upper_m: f64,
            out_raw_m: f64) jni sessionBoundsAt;

    /// The name of the calibration applied to the loaded results (text-output convention;
    /// "" when they are not calibrated or none are loaded).
    fn session_results_calibration(h: SitarHandle) -> String
        => c sitar_session_results_calibration(text) jni sessionResultsCalibration;

    /// Takes a calibration (the JSON file `sitar calibrate` writes, version 2 with a model for
    /// one run) so the walk is coloured the moment it stops, offline: every sub-trajectory
    /// gets the calibrated error and interval of the walk alone, and the markers their places
    /// (results `"source": "walk"`, `"runs": 1`). Given after `stop`, it colours at once
    /// unless the backend's results are loaded; the backend's results replace the walk's when
    /// they arrive. Malformed JSON is `SITAR_ERR_PARSE`; a calibration fitted for another
    /// window (`subtrajectory_frames`) or `pose_relation`, or without a model for one run,
    /// `SITAR_ERR_INVALID_ARGUMENT`, naming what differs; a refused one changes nothing.
    fn session_set_calibration(h: SitarHandle, json: &str)
        => c sitar_session_set_calibration() jni sessionSetCalibration;

    /// Where the loaded results come from. `*out_source`: 1 the walk itself (estimated on the
    /// phone, or by the backend at upload), 2 replays; `*out_target`: 1 the error of the live
    /// run (the user's own walk), 2 the expected error at each place; `*out_runs`: the runs
    /// they come from; `*out_informative`: 1 the calibration's runs predict the error, 0 they
    /// do not (say so: the colours are a guess). 0 (-1 for `*out_informative`) where the
    /// results do not say (legacy CSV) or none are loaded.
    fn session_results_provenance(h: SitarHandle) -> SitarProvenance
        => c sitar_session_results_provenance(out_source: i32, out_target: i32, out_runs: u32,
            out_informative: i32) jni sessionResultsProvenance;

    /// The markers (array-output convention; needs results loaded).
    fn session_markers(h: SitarHandle) -> Vec<SitarMarker>
        => c sitar_session_markers(items: SitarMarker) jni sessionMarkers;

    /// `*out` = 1 if the loaded results are unreliable (mean error at or above
    /// `unreliable_mean_error_m`, or `_deg`), else 0.
    fn session_results_unreliable(h: SitarHandle) -> bool
        => c sitar_session_results_unreliable(out: i32) jni sessionResultsUnreliable;

    /// The class of sub-trajectory `k` (0 unknown, 1 low, 2 medium, 3 high).
    fn session_subtrajectory_class(h: SitarHandle, k: u32) -> i32
        => c sitar_session_subtrajectory_class(out_class: i32) jni sessionSubtrajectoryClass;

    /// Every sub-trajectory's error (NaN if unknown) and class, in order
    /// (array-output convention).
    fn session_subtrajectory_results(h: SitarHandle) -> Vec<SitarSubtrajectoryResult>
        => c sitar_session_subtrajectory_results(items: SitarSubtrajectoryResult)
           jni sessionSubtrajectoryResults;

    /// Render plan: path segments (array-output convention).
    fn session_segments(h: SitarHandle) -> Vec<SitarSegment>
        => c sitar_session_segments(items: SitarSegment);

    /// Render plan: joints between segments (array-output convention).
    fn session_joints(h: SitarHandle) -> Vec<SitarJoint>
        => c sitar_session_joints(items: SitarJoint);

    /// Render plan: camera frustums (array-output convention).
    fn session_frustums(h: SitarHandle) -> Vec<SitarFrustum>
        => c sitar_session_frustums(items: SitarFrustum);

    /// Render plan: start and stop poses. `*out_mask` bit 1 = start written,
    /// bit 2 = stop written.
    fn session_plan_ends(h: SitarHandle) -> PlanEnds
        => c sitar_session_plan_ends(out_start: SitarPose, out_stop: SitarPose, out_mask: u32);

    /// The whole render plan in one flat array (`RenderPlanLayout`).
    fn session_render_plan(h: SitarHandle) -> RenderPlanC
        => jni sessionRenderPlan;

    /// The logged poses as TUM text (text-output convention).
    fn session_trajectory_tum(h: SitarHandle) -> String
        => c sitar_session_trajectory_tum(text) jni sessionTrajectoryTum;

    /// Saves the session into folder `dir` (created if missing).
    fn session_save(h: SitarHandle, dir: &Path)
        => c sitar_session_save() jni sessionSave;

    /// Writes the session's scene as a glTF 2.0 binary file at `path` (`.glb`): trajectory
    /// tube by class, joints, frustums, start/stop, markers and surface points, in glTF's
    /// frame (right-handed, +Y up, metres). `SITAR_ERR_INVALID_STATE` before `start`.
    fn session_export_gltf(h: SitarHandle, path: &Path)
        => c sitar_session_export_gltf() jni sessionExportGltf;

    /// Records an observation of the venue's anchor image `anchor_id` (1…64 bytes of UTF-8,
    /// no comma, quote or control character): `pose` is the pose the platform reports for the
    /// tracked image (world-from-image, the session's convention; image +X to its right),
    /// `tracking` 0 none, 1 limited, 2 full (only full observations align). Saved as
    /// `anchors.csv`. A bad id, a non-finite pose or another tracking value is
    /// `SITAR_ERR_INVALID_ARGUMENT` naming it; before start or after stop
    /// `SITAR_ERR_INVALID_STATE`.
    fn session_anchor(h: SitarHandle, t_ns: i64, anchor_id: &str, pose: &SitarPose,
        tracking: i32)
        => c sitar_session_anchor() jni sessionAnchor;

    /// Loads a venue map (the backend's `GET /v1/venues/{id}/map.json`) and aligns the
    /// session to it from its anchor observations, refined as more arrive. A malformed map is
    /// `SITAR_ERR_PARSE` naming the key; a map of another convention
    /// `SITAR_ERR_INVALID_ARGUMENT`.
    fn session_load_venue(h: SitarHandle, map_json: &str)
        => c sitar_session_load_venue() jni sessionLoadVenue;

    /// The venue's cells in this session's world frame, in the map's order (array-output
    /// convention). `SITAR_ERR_INVALID_STATE` without a venue or before a full observation of
    /// its anchor. Allocation-free.
    fn session_venue_cells(h: SitarHandle, out: Fill<SitarVenueCell>)
        => c sitar_session_venue_cells();

    /// The venue's cells in this session's world frame (`VenueCellLayout` items).
    fn session_venue_cell_list(h: SitarHandle) -> Vec<SitarVenueCell>
        => jni sessionVenueCells;

    /// Where each marker (in `sitar_session_markers` order), then each high-class venue
    /// surface cell (in `sitar_session_venue_cells` order), is shown on a `width_px` ×
    /// `height_px` screen (origin top-left, y down) seen by `camera` (the display-oriented
    /// camera pose, the session's convention) with vertical field of view `vfov_deg`: with
    /// `(x, y, z)` the target in the camera's frame (x right, y up, z along the view) and
    /// `f = (height_px/2) / tan(vfov_deg/2)`, a target with z > 0 projecting onto the
    /// screen at `(width_px/2 + f·x/z, height_px/2 − f·y/z)` is `on_screen = 1` there; any
    /// other is pinned to the ellipse with semi-axes `width_px/2 − margin_px`,
    /// `height_px/2 − margin_px` around the centre in the direction `d = (f·x, −f·y)`
    /// (behind the camera it keeps its side; straight behind, d = 0, it points down).
    /// `angle_rad = atan2(d_y, d_x)`, `distance_m`
    /// from the camera. Array-output convention; pure and allocation-free. vfov outside
    /// (0, 180), a size ≤ 0 or a margin outside [0, half the shorter side) is
    /// `SITAR_ERR_INVALID_ARGUMENT`.
    fn session_guide(h: SitarHandle, camera: &SitarPose, vfov_deg: f64, width_px: i32,
        height_px: i32, margin_px: f64, out: Fill<SitarGuide>)
        => c sitar_session_guide();

    /// Where each marker, then each high venue surface cell, is shown (`GuideLayout` items;
    /// see `sitar_session_guide`).
    fn session_guide_list(h: SitarHandle, camera: &SitarPose, vfov_deg: f64, width_px: i32,
        height_px: i32, margin_px: f64) -> Vec<SitarGuide>
        => jni sessionGuide;

    /// Loads a saved session folder as a new session.
    fn session_load(dir: &Path) -> SitarHandle
        => c sitar_session_load(out: SitarHandle) jni sessionLoad;

    /// Creates a playback-device logger (uses the config's `convention`).
    fn playback_new(config_json: &str) -> SitarHandle
        => c sitar_playback_new(out: SitarHandle) jni playbackNew;

    /// Logs one playback frame's pose.
    fn playback_log(h: SitarHandle, t_ns: i64, pose: &SitarPose)
        => c sitar_playback_log() jni playbackLog;

    /// Number of poses logged.
    fn playback_len(h: SitarHandle) -> usize
        => c sitar_playback_len(out: usize) jni playbackLen;

    /// The logged poses as TUM text (text-output convention).
    fn playback_tum(h: SitarHandle) -> String
        => c sitar_playback_tum(text) jni playbackTum;

    /// Writes `<dir>/trajectory_<index>.txt` (creating `dir`); JNI returns the path.
    fn playback_write(h: SitarHandle, dir: &Path, index: u32) -> std::path::PathBuf
        => c sitar_playback_write() jni playbackWrite;

    /// Frees a playback logger.
    fn playback_free(h: SitarHandle)
        => c sitar_playback_free() jni playbackFree;

    /// Starts uploading `recording_path` in the background and, when the server
    /// is done, loads the results into session `h`. `options_json` (NULL or ""
    /// = defaults): `server_url`, `server_token` (the backend's access token),
    /// `server_cert_sha256` (pin the backend's TLS certificate: its SHA-256
    /// fingerprint as `openssl x509 -fingerprint -sha256` prints it), `trials` (10), `setting` ("trim_mean_30"),
    /// `playback` ("adb"), `poll_interval_ms` (500), `session_id` (continue that
    /// server session, e.g. a failed job's: the upload resumes or is skipped),
    /// `window_frames` and `pose_relation` (the session config's
    /// `subtrajectory_frames` and `pose_relation`; other values are refused),
    /// `evidence_dir` (a saved session folder; default: a started session is
    /// saved as `RECORDING.session/`). The session request carries the config's
    /// `venue` and its `convention` when `arcore`; the folder's `trajectory.txt`,
    /// `subtrajectories.csv` and `anchors.csv` go before the recording (a file the
    /// backend refuses fails the job, naming it; a backend without those routes
    /// is skipped with a logged warning).
    fn upload_start(h: SitarHandle, recording_path: &Path, options_json: Option<&str>)
        -> SitarHandle
        => c sitar_upload_start(out_job: SitarHandle) jni uploadStart;

    /// A snapshot of the job's progress (never blocks on the network).
    fn upload_progress(job: SitarHandle) -> SitarJobProgress
        => c sitar_upload_progress(out: SitarJobProgress) jni uploadProgress;

    /// Why the job failed, "" otherwise (text-output convention).
    fn upload_message(job: SitarHandle) -> String
        => c sitar_upload_message(text) jni uploadMessage;

    /// The server's session id, "" until created (text-output convention).
    fn upload_server_id(job: SitarHandle) -> String
        => c sitar_upload_server_id(text) jni uploadServerId;

    /// Cancels the job: its state is `SITAR_JOB_CANCELLED` at once.
    fn upload_cancel(job: SitarHandle)
        => c sitar_upload_cancel() jni uploadCancel;

    /// Frees the job handle (cancelling it if still running).
    fn upload_free(job: SitarHandle)
        => c sitar_upload_free() jni uploadFree;

    /// Android: unpinned `https://` uses Android's trust store and policy
    /// (rustls-platform-verifier) from now on; call once with the application `Context`
    /// before the first upload (`Sitar.init(context)`). Needs the verifier's Kotlin
    /// component in the app (`rustls:rustls-platform-verifier`); without it, or before
    /// this call, the bundled Mozilla roots are used and the log says why. Returns true
    /// when the platform verifier is in use (the first call decides for the process).
    /// Elsewhere a no-op returning true: the platform verifier is always used there.
    fn platform_tls_init(context: JavaContext) -> bool
        => jni platformTlsInit;

    /// Panics on purpose; returns `SITAR_ERR_PANIC` (feature `testing` only).
    #[cfg(feature = "testing")]
    fn testing_panic()
        => c sitar_testing_panic() jni testingPanic;
}
