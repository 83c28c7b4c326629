//! System trace sections (Perfetto / systrace on Android) around the library's heavier
//! calls, so a developer profiling the app sees where SiTAR's time goes. Never used on the
//! frame path: opening a section allocates its name.

/// An open trace section; it ends when dropped. Off Android, or when tracing is off, it is
/// empty and costs nothing.
#[must_use = "the section ends when this value is dropped"]
pub(crate) struct Section {
    #[cfg(target_os = "android")]
    _inner: Option<ndk::trace::Section>,
}

/// Opens a section named `name` (shown as e.g. `sitar stop` in the trace).
pub(crate) fn section(name: &'static str) -> Section {
    #[cfg(target_os = "android")]
    {
        let inner = if ndk::trace::is_trace_enabled() {
            ndk::trace::Section::new(name).ok()
        } else {
            None
        };
        Section { _inner: inner }
    }
    #[cfg(not(target_os = "android"))]
    {
        let _ = name;
        Section {}
    }
}
