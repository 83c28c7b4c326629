//! JNI entry points for `io.github.sitar.Native` (Kotlin, `android/`): thin
//! wrappers over the bridge. Errors and panics become a thrown
//! `io.github.sitar.SitarException(code, message)`; the function then returns
//! 0 / null. Structs travel as flat `double[]` (layouts documented per
//! function and decoded in `SitarSession.kt`), so native code creates no
//! Kotlin objects except strings, arrays and the exception.

use std::path::Path;

use jni::errors::ErrorPolicy;
use jni::objects::{JByteBuffer, JClass, JDoubleArray, JShortArray, JString, JThrowable};
use jni::sys::{jboolean, jdouble, jint, jlong};
use jni::{jni_sig, jni_str, Env, EnvUnowned, JValue};

use crate::bridge::{self, RenderPlanC};
use crate::error::Error;
use crate::guard::{panic_message, record};
use crate::types::{SitarIntrinsics, SitarPose, SitarSummary};

impl From<jni::errors::Error> for Error {
    fn from(e: jni::errors::Error) -> Self {
        Error::Jni(e.to_string())
    }
}

/// Throws `SitarException(code, message)` for errors and panics.
struct ThrowSitarException;

fn throw(env: &mut Env<'_>, err: &Error) -> jni::errors::Result<()> {
    record(err);
    if env.exception_check() {
        return Ok(()); // a Java exception is already pending: let it win
    }
    let message = env.new_string(err.to_string())?;
    let obj = env.new_object(
        jni_str!("io/github/sitar/SitarException"),
        jni_sig!("(ILjava/lang/String;)V"),
        &[JValue::Int(err.code()), JValue::Object(&message)],
    )?;
    let throwable = env.cast_local::<JThrowable<'_>>(obj)?;
    // `throw` reports the now-pending exception as an error; that is the point.
    let _ = env.throw(throwable);
    Ok(())
}

impl<T: Default> ErrorPolicy<T, Error> for ThrowSitarException {
    type Captures<'unowned_env_local: 'native_method, 'native_method> = ();

    fn on_error<'unowned_env_local: 'native_method, 'native_method>(
        env: &mut Env<'unowned_env_local>,
        _cap: &mut (),
        err: Error,
    ) -> jni::errors::Result<T> {
        throw(env, &err)?;
        Ok(T::default())
    }

    fn on_panic<'unowned_env_local: 'native_method, 'native_method>(
        env: &mut Env<'unowned_env_local>,
        _cap: &mut (),
        payload: Box<dyn std::any::Any + Send + 'static>,
    ) -> jni::errors::Result<T> {
        throw(env, &Error::Panic(panic_message(payload.as_ref())))?;
        Ok(T::default())
    }
}

fn run<'l, T: Default + 'l>(
    env: &mut EnvUnowned<'l>,
    f: impl FnOnce(&mut Env<'l>) -> Result<T, Error>,
) -> T {
    env.with_env(f).resolve::<ThrowSitarException>()
}

fn string(env: &Env<'_>, s: &JString<'_>, name: &'static str) -> Result<String, Error> {
    if s.is_null() {
        return Err(Error::Null(name));
    }
    Ok(s.try_to_string(env)?)
}

fn doubles<'l>(env: &mut Env<'l>, values: &[f64]) -> Result<JDoubleArray<'l>, Error> {
    let array = env.new_double_array(values.len())?;
    array.set_region(env, 0, values)?;
    Ok(array)
}

#[allow(clippy::too_many_arguments)]
fn pose(px: f64, py: f64, pz: f64, qx: f64, qy: f64, qz: f64, qw: f64) -> SitarPose {
    SitarPose {
        px,
        py,
        pz,
        qx,
        qy,
        qz,
        qw,
    }
}

fn handle(h: jlong) -> u64 {
    h as u64
}

fn summary_values(s: &SitarSummary) -> [f64; 7] {
    [
        f64::from(s.frames),
        f64::from(s.midpoints),
        f64::from(s.subtrajectories),
        f64::from(s.depth_samples),
        s.duration_s,
        s.length_m,
        s.mean_depth_m,
    ]
}

/// `String version()`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_version<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
) -> JString<'l> {
    run(&mut env, |env| Ok(env.new_string(bridge::version())?))
}

/// `long sessionNew(String configJson)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionNew<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    config: JString<'l>,
) -> jlong {
    run(&mut env, |env| {
        Ok(bridge::session_new(&string(env, &config, "configJson")?)? as jlong)
    })
}

/// `void sessionFree(long h)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionFree<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) {
    run(&mut env, |_| bridge::session_free(handle(h)))
}

/// `void sessionStart(long h, long tNs, double px, py, pz, qx, qy, qz, qw)`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "system" fn Java_io_github_sitar_Native_sessionStart<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    t_ns: jlong,
    px: jdouble,
    py: jdouble,
    pz: jdouble,
    qx: jdouble,
    qy: jdouble,
    qz: jdouble,
    qw: jdouble,
) {
    run(&mut env, |_| {
        bridge::session_start(handle(h), t_ns, &pose(px, py, pz, qx, qy, qz, qw))
    })
}

/// `int sessionFrame(long h, long tNs, double px, py, pz, qx, qy, qz, qw)`: flags.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "system" fn Java_io_github_sitar_Native_sessionFrame<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    t_ns: jlong,
    px: jdouble,
    py: jdouble,
    pz: jdouble,
    qx: jdouble,
    qy: jdouble,
    qz: jdouble,
    qw: jdouble,
) -> jint {
    run(&mut env, |_| {
        Ok(bridge::session_frame(handle(h), t_ns, &pose(px, py, pz, qx, qy, qz, qw))? as jint)
    })
}

/// `void sessionDepthBuffer(long h, ByteBuffer direct, int w, int h, int strideBytes, double fx, fy, cx, cy, int rotation)`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "system" fn Java_io_github_sitar_Native_sessionDepthBuffer<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    buffer: JByteBuffer<'l>,
    width: jint,
    height: jint,
    row_stride_bytes: jint,
    fx: jdouble,
    fy: jdouble,
    cx: jdouble,
    cy: jdouble,
    rotation: jint,
) {
    run(&mut env, |env| {
        if buffer.is_null() {
            return Err(Error::Null("buffer"));
        }
        let address = env
            .get_direct_buffer_address(&buffer)
            .map_err(|_| Error::invalid("buffer", "the depth ByteBuffer must be direct"))?;
        let capacity = env.get_direct_buffer_capacity(&buffer)?;
        let len = bridge::depth_len(width, height, row_stride_bytes)?;
        if capacity < len * 2 {
            return Err(Error::invalid(
                "buffer",
                format!("{capacity} bytes; a {width}x{height} image with row stride {row_stride_bytes} needs {}", len * 2),
            ));
        }
        if address.is_null() || !address.cast::<u16>().is_aligned() {
            return Err(Error::invalid(
                "buffer",
                "address is NULL or not 2-byte aligned",
            ));
        }
        // SAFETY: a direct buffer of at least the needed bytes, aligned for u16,
        // alive for this call (the Java caller holds it).
        let data = unsafe { std::slice::from_raw_parts(address.cast::<u16>().cast_const(), len) };
        let k = SitarIntrinsics { fx, fy, cx, cy };
        bridge::session_depth(
            handle(h),
            data,
            width as u32,
            height as u32,
            row_stride_bytes as u32,
            &k,
            rotation,
        )
    })
}

/// `void sessionDepthArray(long h, short[] data, int w, int h, int strideBytes, double fx, fy, cx, cy, int rotation)`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "system" fn Java_io_github_sitar_Native_sessionDepthArray<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    array: JShortArray<'l>,
    width: jint,
    height: jint,
    row_stride_bytes: jint,
    fx: jdouble,
    fy: jdouble,
    cx: jdouble,
    cy: jdouble,
    rotation: jint,
) {
    run(&mut env, |env| {
        if array.is_null() {
            return Err(Error::Null("data"));
        }
        let needed = bridge::depth_len(width, height, row_stride_bytes)?;
        let available = array.len(env)?;
        if available < needed {
            return Err(Error::invalid(
                "data",
                format!("{available} shorts; a {width}x{height} image with row stride {row_stride_bytes} bytes needs {needed}"),
            ));
        }
        // SAFETY: read-only access; no JNI calls happen while the critical section is held.
        let elements =
            unsafe { array.get_elements_critical(env, jni::elements::ReleaseMode::NoCopyBack)? };
        // SAFETY: i16 and u16 have the same size and alignment; `needed <= len`.
        let data = unsafe { std::slice::from_raw_parts(elements.as_ptr().cast::<u16>(), needed) };
        let k = SitarIntrinsics { fx, fy, cx, cy };
        bridge::session_depth(
            handle(h),
            data,
            width as u32,
            height as u32,
            row_stride_bytes as u32,
            &k,
            rotation,
        )
    })
}

/// `double[7] sessionStop(long h, long tNs, double px, py, pz, qx, qy, qz, qw)`:
/// frames, midpoints, subtrajectories, depthSamples, durationS, lengthM, meanDepthM.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "system" fn Java_io_github_sitar_Native_sessionStop<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    t_ns: jlong,
    px: jdouble,
    py: jdouble,
    pz: jdouble,
    qx: jdouble,
    qy: jdouble,
    qz: jdouble,
    qw: jdouble,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let s = bridge::session_stop(handle(h), t_ns, &pose(px, py, pz, qx, qy, qz, qw))?;
        doubles(env, &summary_values(&s))
    })
}

/// `double[7] sessionSummary(long h)` (layout as `sessionStop`).
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionSummary<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let s = bridge::session_summary(handle(h))?;
        doubles(env, &summary_values(&s))
    })
}

/// `void sessionLoadResults(long h, String csvOrJson)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionLoadResults<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    text: JString<'l>,
) {
    run(&mut env, |env| {
        bridge::session_load_results(handle(h), &string(env, &text, "csvOrJson")?)
    })
}

/// `double[2] sessionErrorAt(long h, long tNs)`: class, error in metres (NaN if unknown).
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionErrorAt<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    t_ns: jlong,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let (class, error) = bridge::session_error_at(handle(h), t_ns)?;
        doubles(env, &[f64::from(class), error])
    })
}

/// `double[13 n] sessionMarkers(long h)`: per marker px py pz qx qy qz qw nx ny nz class subtrajectory errorM.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionMarkers<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let markers = bridge::session_markers(handle(h))?;
        let flat: Vec<f64> = markers
            .iter()
            .flat_map(|m| {
                [
                    m.px,
                    m.py,
                    m.pz,
                    m.qx,
                    m.qy,
                    m.qz,
                    m.qw,
                    m.nx,
                    m.ny,
                    m.nz,
                    f64::from(m.error_class),
                    f64::from(m.subtrajectory),
                    m.error_m,
                ]
            })
            .collect();
        doubles(env, &flat)
    })
}

/// `boolean sessionResultsUnreliable(long h)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionResultsUnreliable<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> jboolean {
    run(&mut env, |_| bridge::session_results_unreliable(handle(h)))
}

/// `int sessionSubtrajectoryClass(long h, int k)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionSubtrajectoryClass<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    k: jint,
) -> jint {
    run(&mut env, |_| {
        let k = u32::try_from(k).map_err(|_| Error::invalid("k", "must not be negative"))?;
        bridge::session_subtrajectory_class(handle(h), k)
    })
}

/// `double[3 n] sessionSubtrajectoryResults(long h)`: per sub-trajectory errorM (NaN if unknown), subtrajectory, class.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionSubtrajectoryResults<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let results = bridge::session_subtrajectory_results(handle(h))?;
        let flat: Vec<f64> = results
            .iter()
            .flat_map(|r| {
                [
                    r.error_m,
                    f64::from(r.subtrajectory),
                    f64::from(r.error_class),
                ]
            })
            .collect();
        doubles(env, &flat)
    })
}

/// Flattens a render plan: `[nSegments, nJoints, nFrustums, hasStart, hasStop,`
/// segments × (cx cy cz qx qy qz qw length subtrajectory class),
/// joints × (px py pz subtrajectory class),
/// frustums × (px py pz qx qy qz qw subtrajectory class),
/// start pose × 7 if present, stop pose × 7 if present`]`.
pub fn flatten_render_plan(plan: &RenderPlanC) -> Vec<f64> {
    let mut v = vec![
        plan.segments.len() as f64,
        plan.joints.len() as f64,
        plan.frustums.len() as f64,
        f64::from(u8::from(plan.start.is_some())),
        f64::from(u8::from(plan.stop.is_some())),
    ];
    for s in &plan.segments {
        v.extend([
            s.cx,
            s.cy,
            s.cz,
            s.qx,
            s.qy,
            s.qz,
            s.qw,
            s.length,
            f64::from(s.subtrajectory),
            f64::from(s.error_class),
        ]);
    }
    for j in &plan.joints {
        v.extend([
            j.px,
            j.py,
            j.pz,
            f64::from(j.subtrajectory),
            f64::from(j.error_class),
        ]);
    }
    for f in &plan.frustums {
        let p = &f.pose;
        v.extend([
            p.px,
            p.py,
            p.pz,
            p.qx,
            p.qy,
            p.qz,
            p.qw,
            f64::from(f.subtrajectory),
            f64::from(f.error_class),
        ]);
    }
    for p in plan.start.iter().chain(plan.stop.iter()) {
        v.extend([p.px, p.py, p.pz, p.qx, p.qy, p.qz, p.qw]);
    }
    v
}

/// `double[] sessionRenderPlan(long h)`, layout of [`flatten_render_plan`].
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionRenderPlan<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let plan = bridge::session_render_plan(handle(h))?;
        doubles(env, &flatten_render_plan(&plan))
    })
}

/// `String sessionTrajectoryTum(long h)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionTrajectoryTum<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> JString<'l> {
    run(&mut env, |env| {
        Ok(env.new_string(bridge::session_trajectory_tum(handle(h))?)?)
    })
}

/// `void sessionSave(long h, String dir)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionSave<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    dir: JString<'l>,
) {
    run(&mut env, |env| {
        bridge::session_save(handle(h), Path::new(&string(env, &dir, "dir")?))
    })
}

/// `long sessionLoad(String dir)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_sessionLoad<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    dir: JString<'l>,
) -> jlong {
    run(&mut env, |env| {
        Ok(bridge::session_load(Path::new(&string(env, &dir, "dir")?))? as jlong)
    })
}

/// `long playbackNew(String configJson)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_playbackNew<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    config: JString<'l>,
) -> jlong {
    run(&mut env, |env| {
        Ok(bridge::playback_new(&string(env, &config, "configJson")?)? as jlong)
    })
}

/// `void playbackLog(long h, long tNs, double px, py, pz, qx, qy, qz, qw)`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub extern "system" fn Java_io_github_sitar_Native_playbackLog<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    t_ns: jlong,
    px: jdouble,
    py: jdouble,
    pz: jdouble,
    qx: jdouble,
    qy: jdouble,
    qz: jdouble,
    qw: jdouble,
) {
    run(&mut env, |_| {
        bridge::playback_log(handle(h), t_ns, &pose(px, py, pz, qx, qy, qz, qw))
    })
}

/// `long playbackLen(long h)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_playbackLen<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> jlong {
    run(&mut env, |_| Ok(bridge::playback_len(handle(h))? as jlong))
}

/// `String playbackTum(long h)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_playbackTum<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) -> JString<'l> {
    run(&mut env, |env| {
        Ok(env.new_string(bridge::playback_tum(handle(h))?)?)
    })
}

/// `String playbackWrite(long h, String dir, int index)`: the path written.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_playbackWrite<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    dir: JString<'l>,
    index: jint,
) -> JString<'l> {
    run(&mut env, |env| {
        let index =
            u32::try_from(index).map_err(|_| Error::invalid("index", "must not be negative"))?;
        let path = bridge::playback_write(handle(h), Path::new(&string(env, &dir, "dir")?), index)?;
        Ok(env.new_string(path.to_string_lossy())?)
    })
}

/// `void playbackFree(long h)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_playbackFree<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
) {
    run(&mut env, |_| bridge::playback_free(handle(h)))
}

/// `long uploadStart(long session, String recordingPath, String optionsJson)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_uploadStart<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    h: jlong,
    path: JString<'l>,
    options: JString<'l>,
) -> jlong {
    run(&mut env, |env| {
        let path = string(env, &path, "recordingPath")?;
        let options = if options.is_null() {
            String::new()
        } else {
            string(env, &options, "optionsJson")?
        };
        Ok(bridge::upload_start(handle(h), Path::new(&path), &options)? as jlong)
    })
}

/// `double[10] uploadProgress(long job)`: state, errorCode, progress, etaS,
/// bytesSent, bytesTotal, trialsDone, trialsTotal, resultsRevision, resultsTrials.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_uploadProgress<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    job: jlong,
) -> JDoubleArray<'l> {
    run(&mut env, |env| {
        let p = bridge::upload_progress(handle(job))?;
        doubles(
            env,
            &[
                f64::from(p.state),
                f64::from(p.error_code),
                p.progress,
                p.eta_s,
                p.bytes_sent as f64,
                p.bytes_total as f64,
                f64::from(p.trials_done),
                f64::from(p.trials_total),
                f64::from(p.results_revision),
                f64::from(p.results_trials),
            ],
        )
    })
}

/// `String uploadMessage(long job)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_uploadMessage<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    job: jlong,
) -> JString<'l> {
    run(&mut env, |env| {
        Ok(env.new_string(bridge::upload_message(handle(job))?)?)
    })
}

/// `String uploadServerId(long job)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_uploadServerId<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    job: jlong,
) -> JString<'l> {
    run(&mut env, |env| {
        Ok(env.new_string(bridge::upload_server_id(handle(job))?)?)
    })
}

/// `void uploadCancel(long job)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_uploadCancel<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    job: jlong,
) {
    run(&mut env, |_| bridge::upload_cancel(handle(job)))
}

/// `void uploadFree(long job)`.
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_uploadFree<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
    job: jlong,
) {
    run(&mut env, |_| bridge::upload_free(handle(job)))
}

/// `void testingPanic()` (feature `testing`): panics on purpose.
#[cfg(feature = "testing")]
#[no_mangle]
pub extern "system" fn Java_io_github_sitar_Native_testingPanic<'l>(
    mut env: EnvUnowned<'l>,
    _c: JClass<'l>,
) {
    run(&mut env, |_| bridge::testing_panic())
}
