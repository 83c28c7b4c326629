//! Logging goes through `log`; on Android it is routed to logcat once.

/// Installs the platform logger (Android: logcat, tag "sitar"); elsewhere the
/// host application chooses its own `log` backend.
pub(crate) fn init() {
    #[cfg(target_os = "android")]
    android_logger::init_once(
        android_logger::Config::default()
            .with_max_level(log::LevelFilter::Info)
            .with_tag("sitar"),
    );
}
