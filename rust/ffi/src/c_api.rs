//! What the C entry points (`sitar_*`, generated from `exports.rs`) are made of: argument
//! checks and output conventions, plus `sitar_last_error`, the one function written by hand
//! (it reads the guard's message and must not change it, so it is outside the guard).
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

use crate::bridge::{DepthView, PlanEnds, SitarBoundsAt, SitarErrorAt, SitarProvenance};
use crate::error::Error;
use crate::guard::with_last_error;
use crate::types::SitarPose;

pub(crate) fn text_arg<'a>(p: *const c_char, name: &'static str) -> Result<&'a str, Error> {
    if p.is_null() {
        return Err(Error::Null(name));
    }
    // SAFETY: non-NULL; the caller passes a NUL-terminated string valid for the call.
    let bytes = unsafe { CStr::from_ptr(p) };
    bytes
        .to_str()
        .map_err(|source| Error::Utf8 { name, source })
}

/// A string argument that may be NULL (`None`).
pub(crate) fn optional_text_arg<'a>(
    p: *const c_char,
    name: &'static str,
) -> Result<Option<&'a str>, Error> {
    if p.is_null() {
        Ok(None)
    } else {
        text_arg(p, name).map(Some)
    }
}

pub(crate) fn arg<'a, T>(p: *const T, name: &'static str) -> Result<&'a T, Error> {
    // SAFETY: NULL is rejected; otherwise the caller passes a valid, aligned pointer.
    unsafe { p.as_ref() }.ok_or(Error::Null(name))
}

pub(crate) fn out<'a, T>(p: *mut T, name: &'static str) -> Result<&'a mut T, Error> {
    // SAFETY: NULL is rejected; otherwise the caller passes a valid, aligned pointer.
    unsafe { p.as_mut() }.ok_or(Error::Null(name))
}

/// A depth image from a pointer that must hold `(height-1)*row_stride_bytes + width*2` bytes.
pub(crate) fn depth_arg<'a>(
    depth_mm: *const u16,
    width: i32,
    height: i32,
    row_stride_bytes: i32,
) -> Result<DepthView<'a>, Error> {
    if depth_mm.is_null() {
        return Err(Error::Null("depth_mm"));
    }
    if !depth_mm.is_aligned() {
        return Err(Error::invalid("depth_mm", "pointer is not 2-byte aligned"));
    }
    let len = crate::bridge::depth_len(width, height, row_stride_bytes)?;
    // SAFETY: non-NULL, aligned; the caller guarantees the documented size.
    let data = unsafe { std::slice::from_raw_parts(depth_mm, len) };
    DepthView::new(data, width, height, row_stride_bytes)
}

/// The C caller's luminance plane: non-NULL, positive size, stride ≥ width.
pub(crate) fn luma_arg<'a>(
    luma: *const u8,
    width: i32,
    height: i32,
    row_stride_bytes: i32,
) -> Result<crate::bridge::LumaView<'a>, Error> {
    if luma.is_null() {
        return Err(Error::Null("luma"));
    }
    let len = crate::bridge::luma_len(width, height, row_stride_bytes)?;
    // SAFETY: non-NULL; the caller guarantees the documented size.
    let data = unsafe { std::slice::from_raw_parts(luma, len) };
    crate::bridge::LumaView::new(data, width, height, row_stride_bytes)
}

/// An array output `(out, capacity, out_len)` as a [`crate::bridge::Fill`], checked before
/// the work that fills it.
pub(crate) fn fill_arg<'a, T>(
    out_ptr: *mut T,
    capacity: usize,
    out_len: *mut usize,
) -> Result<crate::bridge::Fill<'a, T>, Error> {
    check_array_out(out_ptr, capacity, out_len)?;
    let out_len = out(out_len, "out_len")?;
    let items: &mut [T] = if capacity == 0 {
        &mut []
    } else {
        // SAFETY: non-NULL (checked above for capacity > 0); the caller guarantees room for
        // `capacity` items, valid for the call.
        unsafe { std::slice::from_raw_parts_mut(out_ptr, capacity) }
    };
    Ok(crate::bridge::Fill::new(items, out_len))
}

/// Checks an array output before the work that fills it.
pub(crate) fn check_array_out<T>(
    out_ptr: *mut T,
    capacity: usize,
    out_len: *mut usize,
) -> Result<(), Error> {
    if out_len.is_null() {
        return Err(Error::Null("out_len"));
    }
    if out_ptr.is_null() && capacity > 0 {
        return Err(Error::Null("out"));
    }
    Ok(())
}

pub(crate) fn copy_items<T: Copy>(
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

pub(crate) fn copy_text(
    text: &str,
    buf: *mut c_char,
    cap: usize,
    out_len: *mut usize,
) -> Result<(), Error> {
    check_array_out(buf, cap, out_len)?;
    *out(out_len, "out_len")? = text.len();
    // A truncated copy ends at a character boundary so the buffer stays valid UTF-8.
    let n = char_floor(text, cap.saturating_sub(1));
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

/// The largest `n <= max` at which `text` may be cut without splitting a character.
fn char_floor(text: &str, max: usize) -> usize {
    if max >= text.len() {
        return text.len();
    }
    (0..=max)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0)
}

/// A result written to several output pointers (checked non-NULL beforehand).
pub(crate) trait WriteOuts<Outs> {
    fn write_outs(self, outs: Outs);
}

impl WriteOuts<(&mut i32, &mut f64)> for SitarErrorAt {
    fn write_outs(self, (class, error): (&mut i32, &mut f64)) {
        (*class, *error) = (self.error_class, self.error_m);
    }
}

impl WriteOuts<(&mut i32, &mut f64, &mut f64, &mut f64)> for SitarBoundsAt {
    fn write_outs(self, (present, lower, upper, raw): (&mut i32, &mut f64, &mut f64, &mut f64)) {
        (*present, *lower, *upper, *raw) = (self.present, self.lower_m, self.upper_m, self.raw_m);
    }
}

impl WriteOuts<(&mut i32, &mut i32, &mut u32, &mut i32)> for SitarProvenance {
    fn write_outs(
        self,
        (source, target, runs, informative): (&mut i32, &mut i32, &mut u32, &mut i32),
    ) {
        (*source, *target, *runs, *informative) =
            (self.source, self.target, self.runs, self.informative);
    }
}

/// `*out_mask` bit 1: the start was written; bit 2: the stop was.
impl WriteOuts<(&mut SitarPose, &mut SitarPose, &mut u32)> for PlanEnds {
    fn write_outs(self, (start, stop, mask): (&mut SitarPose, &mut SitarPose, &mut u32)) {
        *mask = 0;
        if let Some(p) = self.start {
            *start = p;
            *mask |= 1;
        }
        if let Some(p) = self.stop {
            *stop = p;
            *mask |= 2;
        }
    }
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
    fn truncated_text_never_splits_a_character() {
        // "aé€😀" = 1 + 2 + 3 + 4 bytes; every capacity leaves valid UTF-8 before the NUL.
        let s = "a\u{e9}\u{20ac}\u{1f600}";
        for cap in 1..=s.len() + 1 {
            let (_, buf, len) = text(s, cap);
            assert_eq!(len, s.len());
            let nul = buf.iter().position(|&b| b == 0).expect("NUL written");
            let copied = std::str::from_utf8(&buf[..nul]).expect("valid UTF-8");
            assert!(s.starts_with(copied), "cap {cap}: {copied:?}");
            assert!(
                copied.len() + 4 > cap.saturating_sub(1),
                "cap {cap}: cut too short"
            );
        }
        let (_, buf, _) = text("\u{e9}\u{e9}", 3);
        assert_eq!(&buf[..], "\u{e9}\0".as_bytes());
        let (_, buf, _) = text("\u{e9}", 2);
        assert_eq!(&buf[..], b"\0\x55");
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
        assert_eq!(crate::bridge::depth_len(160, 120, 320).unwrap(), 160 * 120);
        assert_eq!(crate::bridge::depth_len(3, 2, 8).unwrap(), 4 + 3);
        for (w, h, s) in [(0, 1, 2), (1, 0, 2), (4, 4, 6), (4, 4, 9), (-1, 4, 8)] {
            assert_eq!(
                crate::bridge::depth_len(w, h, s).unwrap_err().status(),
                SITAR_ERR_INVALID_ARGUMENT,
                "{w}x{h} stride {s}"
            );
        }
        let short = [0u16; 5];
        assert_eq!(
            DepthView::new(&short, 3, 2, 8).unwrap_err().status(),
            SITAR_ERR_INVALID_ARGUMENT
        );
        assert!(depth_arg(std::ptr::null(), 3, 2, 8).is_err());
    }

    #[test]
    fn several_outputs_are_written_and_absent_ends_left_alone() {
        let (mut class, mut error) = (0, 0.0);
        SitarErrorAt {
            error_class: 3,
            error_m: 0.2,
        }
        .write_outs((&mut class, &mut error));
        assert_eq!((class, error), (3, 0.2));
        let (mut present, mut lower, mut upper, mut raw) = (7, 0.0, 0.0, 0.0);
        SitarBoundsAt {
            present: 1,
            lower_m: 0.01,
            upper_m: 0.3,
            raw_m: f64::NAN,
        }
        .write_outs((&mut present, &mut lower, &mut upper, &mut raw));
        assert_eq!((present, lower, upper), (1, 0.01, 0.3));
        assert!(raw.is_nan());
        let (mut source, mut target, mut runs, mut informative) = (9, 9, 9, 9);
        SitarProvenance {
            source: 1,
            target: 2,
            runs: 5,
            informative: -1,
        }
        .write_outs((&mut source, &mut target, &mut runs, &mut informative));
        assert_eq!((source, target, runs, informative), (1, 2, 5, -1));
        let marker = SitarPose {
            px: -7.0,
            ..SitarPose::default()
        };
        let (mut start, mut stop, mut mask) = (marker, marker, 9);
        let stop_pose = SitarPose {
            qw: 1.0,
            ..SitarPose::default()
        };
        PlanEnds {
            start: None,
            stop: Some(stop_pose),
        }
        .write_outs((&mut start, &mut stop, &mut mask));
        assert_eq!((start, stop, mask), (marker, stop_pose, 2));
    }
}
