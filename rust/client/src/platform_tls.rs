//! Which roots check an unpinned `https://` server, and the process-wide Android switch.
//!
//! On the host the platform's verifier (rustls-platform-verifier) is always used. On Android
//! that verifier calls into the JVM, so it needs a JNI init with the app's `Context` and its
//! Kotlin component in the app; until the native library reports a successful init
//! ([`set_android_platform_verifier`]), the bundled Mozilla roots (`webpki-roots`) are used
//! instead, and the first agent made says why, once, in the log.

use std::sync::{Once, OnceLock};

/// The set of roots an unpinned `https://` URL is checked against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Roots {
    /// The platform's verifier: its trust store, enterprise CAs and policy.
    PlatformVerifier,
    /// Mozilla's roots bundled with the library (`webpki-roots`).
    Bundled,
}

/// The operating-system family that decides how the platform verifier is reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetOs {
    /// Android: the verifier needs the JNI init first.
    Android,
    /// Every other target: the verifier works as is.
    Other,
}

impl TargetOs {
    /// The target this library was built for.
    pub const fn current() -> Self {
        if cfg!(target_os = "android") {
            TargetOs::Android
        } else {
            TargetOs::Other
        }
    }
}

/// The choice itself, a pure function so both branches are testable on any host:
/// Android uses the platform verifier only after its init succeeded.
pub const fn choose_roots(os: TargetOs, android_initialised: bool) -> Roots {
    match os {
        TargetOs::Other => Roots::PlatformVerifier,
        TargetOs::Android if android_initialised => Roots::PlatformVerifier,
        TargetOs::Android => Roots::Bundled,
    }
}

/// The outcome of the Android init: `Ok` once it succeeded, `Err(why)` when it failed. Set
/// once per process (the verifier's own JNI state is set once too).
static ANDROID_INIT: OnceLock<Result<(), String>> = OnceLock::new();

/// Records the outcome of the Android platform verifier's init (called by the native
/// library's `Sitar.init(context)`). The first outcome wins: a later call changes nothing
/// and returns the recorded outcome, so agents made before and after agree.
pub fn set_android_platform_verifier(outcome: Result<(), String>) -> Result<(), String> {
    ANDROID_INIT
        .get_or_init(|| {
            if let Err(why) = &outcome {
                log::warn!(
                    "Android platform TLS roots unavailable, keeping the bundled roots: {why}"
                );
            }
            outcome
        })
        .clone()
}

/// The recorded outcome of the Android init, `None` before any.
pub fn android_init_outcome() -> Option<Result<(), String>> {
    ANDROID_INIT.get().cloned()
}

/// The roots for a new agent on this target, logging once why the bundled roots are used
/// when they are.
pub(crate) fn current_roots() -> Roots {
    let roots = choose_roots(
        TargetOs::current(),
        matches!(ANDROID_INIT.get(), Some(Ok(()))),
    );
    if roots == Roots::Bundled {
        static SAID: Once = Once::new();
        SAID.call_once(|| {
            let why = match ANDROID_INIT.get() {
                Some(Err(why)) => why.as_str(),
                _ => "Sitar.init(context) was not called before the first connection",
            };
            log::info!(
                "unpinned https uses the bundled Mozilla roots, not Android's trust store: {why}"
            );
        });
    }
    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn android_uses_the_bundled_roots_until_its_init_succeeded() {
        assert_eq!(choose_roots(TargetOs::Android, false), Roots::Bundled);
        assert_eq!(
            choose_roots(TargetOs::Android, true),
            Roots::PlatformVerifier
        );
    }

    #[test]
    fn other_targets_always_use_the_platform_verifier() {
        assert_eq!(
            choose_roots(TargetOs::Other, false),
            Roots::PlatformVerifier
        );
        assert_eq!(choose_roots(TargetOs::Other, true), Roots::PlatformVerifier);
    }

    #[test]
    fn the_first_init_outcome_wins() {
        // Process-wide, but on this host the roots do not depend on it.
        let first = set_android_platform_verifier(Err("no Kotlin component".into()));
        assert_eq!(first, Err("no Kotlin component".to_string()));
        assert_eq!(
            set_android_platform_verifier(Ok(())),
            Err("no Kotlin component".to_string())
        );
        assert_eq!(
            android_init_outcome(),
            Some(Err("no Kotlin component".to_string()))
        );
    }

    #[cfg(not(target_os = "android"))]
    #[test]
    fn this_host_uses_the_platform_verifier_without_any_init() {
        assert_eq!(TargetOs::current(), TargetOs::Other);
        assert_eq!(current_roots(), Roots::PlatformVerifier);
    }
}
