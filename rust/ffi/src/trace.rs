//! System trace sections (Perfetto / systrace on Android) around the library's heavier
//! calls, so a developer profiling the app sees where SiTAR's time goes. Never used on the
//! frame path: opening a section allocates its name.
//!
//! The NDK's `ATrace_*` functions live in libandroid.so; they are looked up once with
//! `dlopen`/`dlsym` (bionic's libdl) rather than linked, so the library needs nothing from
//! the phone beyond libc, libm, libdl and liblog (`scripts/check-android` checks its
//! DT_NEEDED), and a phone without them simply traces nothing.

/// An open trace section; it ends when dropped. Off Android, or when tracing is off, it is
/// empty and costs nothing.
#[must_use = "the section ends when this value is dropped"]
pub(crate) struct Section {
    #[cfg(target_os = "android")]
    open: bool,
}

/// Opens a section named `name` (shown as e.g. `sitar stop` in the trace).
pub(crate) fn section(name: &'static str) -> Section {
    #[cfg(target_os = "android")]
    {
        Section {
            open: atrace::begin(name),
        }
    }
    #[cfg(not(target_os = "android"))]
    {
        let _ = name;
        Section {}
    }
}

#[cfg(target_os = "android")]
impl Drop for Section {
    fn drop(&mut self) {
        if self.open {
            atrace::end();
        }
    }
}

#[cfg(target_os = "android")]
mod atrace {
    use std::ffi::{c_char, c_int, c_void, CString};
    use std::sync::OnceLock;

    type BeginSection = unsafe extern "C" fn(*const c_char);
    type EndSection = unsafe extern "C" fn();
    type IsEnabled = unsafe extern "C" fn() -> bool;

    /// The three functions of `<android/trace.h>` (API 23), when libandroid has them.
    struct Api {
        begin: BeginSection,
        end: EndSection,
        enabled: IsEnabled,
    }

    const RTLD_NOW: c_int = 2;

    unsafe extern "C" {
        fn dlopen(filename: *const c_char, flags: c_int) -> *mut c_void;
        fn dlsym(handle: *mut c_void, symbol: *const c_char) -> *mut c_void;
    }

    fn api() -> Option<&'static Api> {
        static API: OnceLock<Option<Api>> = OnceLock::new();
        API.get_or_init(|| {
            // SAFETY: dlopen and dlsym take NUL-terminated names; the handle is never closed,
            // so the function pointers stay valid for the life of the process; each symbol is
            // cast to the signature <android/trace.h> declares for it.
            unsafe {
                let lib = dlopen(c"libandroid.so".as_ptr(), RTLD_NOW);
                if lib.is_null() {
                    return None;
                }
                let begin = dlsym(lib, c"ATrace_beginSection".as_ptr());
                let end = dlsym(lib, c"ATrace_endSection".as_ptr());
                let enabled = dlsym(lib, c"ATrace_isEnabled".as_ptr());
                if begin.is_null() || end.is_null() || enabled.is_null() {
                    return None;
                }
                Some(Api {
                    begin: std::mem::transmute::<*mut c_void, BeginSection>(begin),
                    end: std::mem::transmute::<*mut c_void, EndSection>(end),
                    enabled: std::mem::transmute::<*mut c_void, IsEnabled>(enabled),
                })
            }
        })
        .as_ref()
    }

    /// Begins a section when tracing is on; whether one was begun.
    pub(super) fn begin(name: &str) -> bool {
        let Some(api) = api() else { return false };
        // SAFETY: the functions come from libandroid as looked up above; the name is a
        // NUL-terminated string that outlives the call (ATrace copies it).
        unsafe {
            if !(api.enabled)() {
                return false;
            }
            let Ok(name) = CString::new(name) else {
                return false;
            };
            (api.begin)(name.as_ptr());
        }
        true
    }

    /// Ends the section [`begin`] began.
    pub(super) fn end() {
        if let Some(api) = api() {
            // SAFETY: as in `begin`; called once per begun section, on the same thread (the
            // section is a local value of the call it traces).
            unsafe { (api.end)() }
        }
    }
}
