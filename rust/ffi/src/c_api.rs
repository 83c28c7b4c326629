//! The C ABI: thin `extern "C"` wrappers over the bridge. Every function
//! returns a `SitarStatus` code (0 ok, negative error) and goes through the
//! guard; outputs go through pointers that must be valid for the call.
//!
//! Conventions beyond ARCHITECTURE.md, applied everywhere:
//! - Array outputs `(out, capacity, out_len)`: `*out_len` always receives the
//!   number of items; if `capacity` is smaller the call returns
//!   `SITAR_ERR_BUFFER_TOO_SMALL` and writes no items. `out` may be NULL only
//!   when `capacity` is 0 (a size query).
//! - Text outputs `(buf, cap, out_len)`: UTF-8, NUL-terminated; `*out_len`
//!   receives the length in bytes without the NUL; if `cap < *out_len + 1`
//!   the call returns `SITAR_ERR_BUFFER_TOO_SMALL` and, if `cap > 0`, writes
//!   the NUL-terminated prefix that fits.
//! - Output pointers are checked before any work is done, so a NULL output
//!   never leaks an object.

// These functions are called from C and C#, where `unsafe fn` means nothing;
// each checks its pointers for NULL and documents what else it needs.
#![allow(clippy::not_unsafe_ptr_arg_deref)]

use std::ffi::{c_char, CStr};
use std::path::Path;

use crate::bridge;
use crate::error::Error;
use crate::guard::{run_ffi_safe, with_last_error};
use crate::registry::SitarHandle;
use crate::types::{
    SitarFrustum, SitarIntrinsics, SitarJobProgress, SitarJoint, SitarMarker, SitarPose,
    SitarSegment, SitarSubtrajectoryResult, SitarSummary,
};

fn text_arg<'a>(p: *const c_char, name: &'static str) -> Result<&'a str, Error> {
    if p.is_null() {
        return Err(Error::Null(name));
    }
    // SAFETY: non-NULL; the caller passes a NUL-terminated string valid for the call.
    let bytes = unsafe { CStr::from_ptr(p) };
    bytes
        .to_str()
        .map_err(|source| Error::Utf8 { name, source })
}

fn arg<'a, T>(p: *const T, name: &'static str) -> Result<&'a T, Error> {
    // SAFETY: NULL is rejected; otherwise the caller passes a valid, aligned pointer.
    unsafe { p.as_ref() }.ok_or(Error::Null(name))
}

fn out<'a, T>(p: *mut T, name: &'static str) -> Result<&'a mut T, Error> {
    // SAFETY: NULL is rejected; otherwise the caller passes a valid, aligned pointer.
    unsafe { p.as_mut() }.ok_or(Error::Null(name))
}

/// Checks an array output before the work that fills it.
fn check_array_out<T>(out_ptr: *mut T, capacity: usize, out_len: *mut usize) -> Result<(), Error> {
    if out_len.is_null() {
        return Err(Error::Null("out_len"));
    }
    if out_ptr.is_null() && capacity > 0 {
        return Err(Error::Null("out"));
    }
    Ok(())
}

fn copy_items<T: Copy>(
    items: &[T],
    out_ptr: *mut T,
    capacity: usize,
    out_len: *mut usize,
) -> Result<(), Error> {
    check_array_out(out_ptr, capacity, out_len)?;
    *out(out_len, "out_len")? = items.len();
    if items.len() > capacity {
        return Err(Error::BufferTooSmall {
            needed: items.len(),
            capacity,
        });
    }
    if !items.is_empty() {
        // SAFETY: `out_ptr` is non-NULL (capacity >= len > 0) and the caller
        // guarantees room for `capacity` items.
        unsafe { std::ptr::copy_nonoverlapping(items.as_ptr(), out_ptr, items.len()) };
    }
    Ok(())
}

fn copy_text(text: &str, buf: *mut c_char, cap: usize, out_len: *mut usize) -> Result<(), Error> {
    check_array_out(buf, cap, out_len)?;
    *out(out_len, "out_len")? = text.len();
    let n = text.len().min(cap.saturating_sub(1));
    if cap > 0 {
        // SAFETY: `buf` is non-NULL (cap > 0) with room for `cap` bytes; n + 1 <= cap.
        unsafe {
            std::ptr::copy_nonoverlapping(text.as_ptr(), buf.cast::<u8>(), n);
            *buf.add(n) = 0;
        }
    }
    if text.len() + 1 > cap {
        return Err(Error::BufferTooSmall {
            needed: text.len() + 1,
            capacity: cap,
        });
    }
    Ok(())
}

/// The library version as a static NUL-terminated string (never freed).
#[no_mangle]
pub extern "C" fn sitar_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// Copies the calling thread's last error message (see the text-output
/// convention). It never changes the stored message itself; "" if none yet.
#[no_mangle]
pub extern "C" fn sitar_last_error(buf: *mut c_char, cap: usize, out_len: *mut usize) -> i32 {
    match std::panic::catch_unwind(|| with_last_error(|msg| copy_text(msg, buf, cap, out_len))) {
        Ok(Ok(())) => 0,
        Ok(Err(e)) => e.code(),
        Err(_) => crate::SitarStatus::SITAR_ERR_PANIC as i32,
    }
}

/// Creates a session from a JSON config (every key optional; "" = defaults).
#[no_mangle]
pub extern "C" fn sitar_session_new(config_json: *const c_char, out: *mut SitarHandle) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::session_new(text_arg(config_json, "config_json")?)?;
        Ok(())
    })
}

/// Frees a session; any later use of the handle is `SITAR_ERR_INVALID_HANDLE`.
#[no_mangle]
pub extern "C" fn sitar_session_free(h: SitarHandle) -> i32 {
    run_ffi_safe(|| bridge::session_free(h))
}

/// Starts recording at `t_ns` with `pose` (frame 0).
#[no_mangle]
pub extern "C" fn sitar_session_start(h: SitarHandle, t_ns: i64, pose: *const SitarPose) -> i32 {
    run_ffi_safe(|| bridge::session_start(h, t_ns, arg(pose, "pose")?))
}

/// One camera frame. `*out_flags`: 1 = midpoint (give depth), 2 = endpoint.
/// Allocation-free on non-logging frames.
#[no_mangle]
pub extern "C" fn sitar_session_frame(
    h: SitarHandle,
    t_ns: i64,
    pose: *const SitarPose,
    out_flags: *mut u32,
) -> i32 {
    run_ffi_safe(|| {
        let out_flags = out(out_flags, "out_flags")?;
        *out_flags = bridge::session_frame(h, t_ns, arg(pose, "pose")?)?;
        Ok(())
    })
}

/// The depth image (16-bit millimetres, sensor orientation) for the last
/// midpoint. `depth_mm` must hold `(height-1)*row_stride_bytes + width*2` bytes.
#[no_mangle]
pub extern "C" fn sitar_session_depth(
    h: SitarHandle,
    depth_mm: *const u16,
    width: i32,
    height: i32,
    row_stride_bytes: i32,
    k: *const SitarIntrinsics,
    display_rotation: i32,
) -> i32 {
    run_ffi_safe(|| {
        if depth_mm.is_null() {
            return Err(Error::Null("depth_mm"));
        }
        if !depth_mm.is_aligned() {
            return Err(Error::invalid("depth_mm", "pointer is not 2-byte aligned"));
        }
        let k = arg(k, "k")?;
        let len = bridge::depth_len(width, height, row_stride_bytes)?;
        // SAFETY: non-NULL, aligned; the caller guarantees the documented size.
        let data = unsafe { std::slice::from_raw_parts(depth_mm, len) };
        bridge::session_depth(
            h,
            data,
            width as u32,
            height as u32,
            row_stride_bytes as u32,
            k,
            display_rotation,
        )
    })
}

/// Stops recording and writes the summary.
#[no_mangle]
pub extern "C" fn sitar_session_stop(
    h: SitarHandle,
    t_ns: i64,
    pose: *const SitarPose,
    out: *mut SitarSummary,
) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::session_stop(h, t_ns, arg(pose, "pose")?)?;
        Ok(())
    })
}

/// The summary of a stopped recording (`SITAR_ERR_INVALID_STATE` before stop).
#[no_mangle]
pub extern "C" fn sitar_session_summary(h: SitarHandle, out: *mut SitarSummary) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::session_summary(h)?;
        Ok(())
    })
}

/// Loads results: legacy CSV (`start,error`) or JSON, autodetected.
#[no_mangle]
pub extern "C" fn sitar_session_load_results(h: SitarHandle, csv_or_json: *const c_char) -> i32 {
    run_ffi_safe(|| bridge::session_load_results(h, text_arg(csv_or_json, "csv_or_json")?))
}

/// The error class at `t_ns` (0 unknown, 1 low, 2 medium, 3 high) and the
/// error in metres (NaN when unknown).
#[no_mangle]
pub extern "C" fn sitar_session_error_at(
    h: SitarHandle,
    t_ns: i64,
    out_class: *mut i32,
    out_error_m: *mut f64,
) -> i32 {
    run_ffi_safe(|| {
        let out_class = out(out_class, "out_class")?;
        let out_error_m = out(out_error_m, "out_error_m")?;
        (*out_class, *out_error_m) = bridge::session_error_at(h, t_ns)?;
        Ok(())
    })
}

/// The markers (array-output convention; needs results loaded).
#[no_mangle]
pub extern "C" fn sitar_session_markers(
    h: SitarHandle,
    out: *mut SitarMarker,
    capacity: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(out, capacity, out_len)?;
        copy_items(&bridge::session_markers(h)?, out, capacity, out_len)
    })
}

/// `*out` = 1 if the loaded results are unreliable (mean error at or above
/// `unreliable_mean_error_m`), else 0.
#[no_mangle]
pub extern "C" fn sitar_session_results_unreliable(h: SitarHandle, out: *mut i32) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = i32::from(bridge::session_results_unreliable(h)?);
        Ok(())
    })
}

/// The class of sub-trajectory `k` (0 unknown, 1 low, 2 medium, 3 high).
#[no_mangle]
pub extern "C" fn sitar_session_subtrajectory_class(
    h: SitarHandle,
    k: u32,
    out_class: *mut i32,
) -> i32 {
    run_ffi_safe(|| {
        let out_class = out(out_class, "out_class")?;
        *out_class = bridge::session_subtrajectory_class(h, k)?;
        Ok(())
    })
}

/// Every sub-trajectory's error (NaN if unknown) and class, in order
/// (array-output convention).
#[no_mangle]
pub extern "C" fn sitar_session_subtrajectory_results(
    h: SitarHandle,
    out: *mut SitarSubtrajectoryResult,
    capacity: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(out, capacity, out_len)?;
        copy_items(
            &bridge::session_subtrajectory_results(h)?,
            out,
            capacity,
            out_len,
        )
    })
}

/// Render plan: path segments (array-output convention).
#[no_mangle]
pub extern "C" fn sitar_session_segments(
    h: SitarHandle,
    out: *mut SitarSegment,
    capacity: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(out, capacity, out_len)?;
        copy_items(
            &bridge::session_render_plan(h)?.segments,
            out,
            capacity,
            out_len,
        )
    })
}

/// Render plan: joints between segments (array-output convention).
#[no_mangle]
pub extern "C" fn sitar_session_joints(
    h: SitarHandle,
    out: *mut SitarJoint,
    capacity: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(out, capacity, out_len)?;
        copy_items(
            &bridge::session_render_plan(h)?.joints,
            out,
            capacity,
            out_len,
        )
    })
}

/// Render plan: camera frustums (array-output convention).
#[no_mangle]
pub extern "C" fn sitar_session_frustums(
    h: SitarHandle,
    out: *mut SitarFrustum,
    capacity: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(out, capacity, out_len)?;
        copy_items(
            &bridge::session_render_plan(h)?.frustums,
            out,
            capacity,
            out_len,
        )
    })
}

/// Render plan: start and stop poses. `*out_mask` bit 1 = start written,
/// bit 2 = stop written.
#[no_mangle]
pub extern "C" fn sitar_session_plan_ends(
    h: SitarHandle,
    out_start: *mut SitarPose,
    out_stop: *mut SitarPose,
    out_mask: *mut u32,
) -> i32 {
    run_ffi_safe(|| {
        let out_start = out(out_start, "out_start")?;
        let out_stop = out(out_stop, "out_stop")?;
        let out_mask = out(out_mask, "out_mask")?;
        let plan = bridge::session_render_plan(h)?;
        *out_mask = 0;
        if let Some(p) = plan.start {
            *out_start = p;
            *out_mask |= 1;
        }
        if let Some(p) = plan.stop {
            *out_stop = p;
            *out_mask |= 2;
        }
        Ok(())
    })
}

/// The logged poses as TUM text (text-output convention).
#[no_mangle]
pub extern "C" fn sitar_session_trajectory_tum(
    h: SitarHandle,
    buf: *mut c_char,
    cap: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(buf, cap, out_len)?;
        copy_text(&bridge::session_trajectory_tum(h)?, buf, cap, out_len)
    })
}

/// Saves the session into folder `dir` (created if missing).
#[no_mangle]
pub extern "C" fn sitar_session_save(h: SitarHandle, dir: *const c_char) -> i32 {
    run_ffi_safe(|| bridge::session_save(h, Path::new(text_arg(dir, "dir")?)))
}

/// Loads a saved session folder as a new session.
#[no_mangle]
pub extern "C" fn sitar_session_load(dir: *const c_char, out: *mut SitarHandle) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::session_load(Path::new(text_arg(dir, "dir")?))?;
        Ok(())
    })
}

/// Creates a playback-device logger (uses the config's `convention`).
#[no_mangle]
pub extern "C" fn sitar_playback_new(config_json: *const c_char, out: *mut SitarHandle) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::playback_new(text_arg(config_json, "config_json")?)?;
        Ok(())
    })
}

/// Logs one playback frame's pose.
#[no_mangle]
pub extern "C" fn sitar_playback_log(h: SitarHandle, t_ns: i64, pose: *const SitarPose) -> i32 {
    run_ffi_safe(|| bridge::playback_log(h, t_ns, arg(pose, "pose")?))
}

/// Number of poses logged.
#[no_mangle]
pub extern "C" fn sitar_playback_len(h: SitarHandle, out: *mut usize) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::playback_len(h)?;
        Ok(())
    })
}

/// The logged poses as TUM text (text-output convention).
#[no_mangle]
pub extern "C" fn sitar_playback_tum(
    h: SitarHandle,
    buf: *mut c_char,
    cap: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(buf, cap, out_len)?;
        copy_text(&bridge::playback_tum(h)?, buf, cap, out_len)
    })
}

/// Writes `<dir>/trajectory_<index>.txt` (creating `dir`).
#[no_mangle]
pub extern "C" fn sitar_playback_write(h: SitarHandle, dir: *const c_char, index: u32) -> i32 {
    run_ffi_safe(|| bridge::playback_write(h, Path::new(text_arg(dir, "dir")?), index).map(drop))
}

/// Frees a playback logger.
#[no_mangle]
pub extern "C" fn sitar_playback_free(h: SitarHandle) -> i32 {
    run_ffi_safe(|| bridge::playback_free(h))
}

/// Starts uploading `recording_path` in the background and, when the server
/// is done, loads the results into session `h`. `options_json` (NULL or ""
/// = defaults): `server_url`, `trials` (10), `setting` ("trim_mean_30"),
/// `playback` ("adb"), `poll_interval_ms` (500), `session_id` (continue that
/// server session, e.g. a failed job's: the upload resumes or is skipped).
#[no_mangle]
pub extern "C" fn sitar_upload_start(
    h: SitarHandle,
    recording_path: *const c_char,
    options_json: *const c_char,
    out_job: *mut SitarHandle,
) -> i32 {
    run_ffi_safe(|| {
        let out_job = out(out_job, "out_job")?;
        let options = if options_json.is_null() {
            ""
        } else {
            text_arg(options_json, "options_json")?
        };
        *out_job = bridge::upload_start(
            h,
            Path::new(text_arg(recording_path, "recording_path")?),
            options,
        )?;
        Ok(())
    })
}

/// A snapshot of the job's progress (never blocks on the network).
#[no_mangle]
pub extern "C" fn sitar_upload_progress(job: SitarHandle, out: *mut SitarJobProgress) -> i32 {
    run_ffi_safe(|| {
        let out = self::out(out, "out")?;
        *out = bridge::upload_progress(job)?;
        Ok(())
    })
}

/// Why the job failed, "" otherwise (text-output convention).
#[no_mangle]
pub extern "C" fn sitar_upload_message(
    job: SitarHandle,
    buf: *mut c_char,
    cap: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(buf, cap, out_len)?;
        copy_text(&bridge::upload_message(job)?, buf, cap, out_len)
    })
}

/// The server's session id, "" until created (text-output convention).
#[no_mangle]
pub extern "C" fn sitar_upload_server_id(
    job: SitarHandle,
    buf: *mut c_char,
    cap: usize,
    out_len: *mut usize,
) -> i32 {
    run_ffi_safe(|| {
        check_array_out(buf, cap, out_len)?;
        copy_text(&bridge::upload_server_id(job)?, buf, cap, out_len)
    })
}

/// Cancels the job: its state is `SITAR_JOB_CANCELLED` at once.
#[no_mangle]
pub extern "C" fn sitar_upload_cancel(job: SitarHandle) -> i32 {
    run_ffi_safe(|| bridge::upload_cancel(job))
}

/// Frees the job handle (cancelling it if still running).
#[no_mangle]
pub extern "C" fn sitar_upload_free(job: SitarHandle) -> i32 {
    run_ffi_safe(|| bridge::upload_free(job))
}

/// Panics on purpose; returns `SITAR_ERR_PANIC` (feature `testing` only).
#[cfg(feature = "testing")]
#[no_mangle]
pub extern "C" fn sitar_testing_panic() -> i32 {
    run_ffi_safe(bridge::testing_panic)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SitarStatus::*;

    fn text(s: &str, cap: usize) -> (Result<(), Error>, Vec<u8>, usize) {
        let mut buf = vec![0x55u8; cap];
        let mut len = usize::MAX;
        let ptr = if cap == 0 {
            std::ptr::null_mut()
        } else {
            buf.as_mut_ptr().cast()
        };
        let r = copy_text(s, ptr, cap, &mut len);
        (r, buf, len)
    }

    #[test]
    fn text_output_fits_exactly_or_truncates_with_a_nul() {
        let (r, buf, len) = text("abc", 4);
        assert!(r.is_ok());
        assert_eq!((&buf[..], len), (&b"abc\0"[..], 3));
        let (r, buf, len) = text("abc", 3);
        assert_eq!(r.unwrap_err().status(), SITAR_ERR_BUFFER_TOO_SMALL);
        assert_eq!((&buf[..], len), (&b"ab\0"[..], 3));
        let (r, buf, len) = text("abc", 1);
        assert_eq!(r.unwrap_err().status(), SITAR_ERR_BUFFER_TOO_SMALL);
        assert_eq!((&buf[..], len), (&b"\0"[..], 3));
        let (r, _, len) = text("", 0);
        assert_eq!(r.unwrap_err().status(), SITAR_ERR_BUFFER_TOO_SMALL);
        assert_eq!(len, 0);
    }

    #[test]
    fn array_output_writes_all_or_nothing() {
        let items = [1u32, 2, 3];
        let mut out = [9u32; 3];
        let mut len = 0;
        let r = copy_items(&items, out.as_mut_ptr(), 2, &mut len);
        assert_eq!(r.unwrap_err().status(), SITAR_ERR_BUFFER_TOO_SMALL);
        assert_eq!((out, len), ([9, 9, 9], 3));
        copy_items(&items, out.as_mut_ptr(), 3, &mut len).unwrap();
        assert_eq!((out, len), ([1, 2, 3], 3));
        copy_items(&[] as &[u32], std::ptr::null_mut(), 0, &mut len).unwrap();
        assert_eq!(len, 0);
        let r = copy_items(&items, std::ptr::null_mut(), 3, &mut len);
        assert_eq!(r.unwrap_err().status(), SITAR_ERR_NULL);
        let r = copy_items(&items, out.as_mut_ptr(), 3, std::ptr::null_mut());
        assert_eq!(r.unwrap_err().status(), SITAR_ERR_NULL);
    }

    #[test]
    fn depth_geometry_is_checked() {
        assert_eq!(bridge::depth_len(160, 120, 320).unwrap(), 160 * 120);
        assert_eq!(bridge::depth_len(3, 2, 8).unwrap(), 4 + 3);
        for (w, h, s) in [(0, 1, 2), (1, 0, 2), (4, 4, 6), (4, 4, 9), (-1, 4, 8)] {
            assert_eq!(
                bridge::depth_len(w, h, s).unwrap_err().status(),
                SITAR_ERR_INVALID_ARGUMENT,
                "{w}x{h} stride {s}"
            );
        }
    }
}
