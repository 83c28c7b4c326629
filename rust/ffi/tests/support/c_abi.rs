//! What the C ABI tests share: the status codes and the thread's last error message.
#![allow(dead_code)] // each test uses some of them

use std::ffi::c_char;

pub const OK: i32 = 0;
pub const ERR_NULL: i32 = -1;
pub const ERR_INVALID_ARGUMENT: i32 = -2;
pub const ERR_INVALID_HANDLE: i32 = -3;
pub const ERR_INVALID_STATE: i32 = -4;
pub const ERR_PARSE: i32 = -5;
pub const ERR_BUFFER_TOO_SMALL: i32 = -8;

/// `sitar_last_error` as a string.
pub fn last_error() -> String {
    let mut buf = [0 as c_char; 512];
    let mut len = 0usize;
    sitar::sitar_last_error(buf.as_mut_ptr(), buf.len(), &mut len);
    let bytes: Vec<u8> = buf[..len].iter().map(|&c| c as u8).collect();
    String::from_utf8(bytes).unwrap()
}
