//! `Native.platformTlsInit(context)`: hands the app's `Context` to rustls-platform-verifier
//! so that unpinned `https://` on Android is checked by Android's own trust store and
//! policy instead of the bundled Mozilla roots (`sitar_client::platform_tls`).
//!
//! The init needs the verifier's Kotlin component (`org.rustls.platformverifier`, the
//! `rustls:rustls-platform-verifier` AAR) in the app: without it every later handshake would
//! fail, so its class is loaded first through the app's class loader, and when that fails
//! the bundled roots stay and the reason goes to the log. On the host the platform verifier
//! is always in use and this is a no-op.

use jni::objects::JObject;
use jni::Env;

use crate::error::Error;

/// The app's `android.content.Context` as a JNI entry point received it, with the `Env` of
/// that call (the conversion of a `JavaContext` parameter in `exports_macro.rs`).
pub(crate) struct JavaContext<'a, 'l> {
    #[cfg_attr(not(target_os = "android"), allow(dead_code))]
    env: &'a mut Env<'l>,
    #[cfg_attr(not(target_os = "android"), allow(dead_code))]
    context: JObject<'l>,
}

impl<'a, 'l> JavaContext<'a, 'l> {
    /// A non-null object from Kotlin; the init itself checks that it is a `Context`.
    pub(crate) fn new(
        env: &'a mut Env<'l>,
        context: JObject<'l>,
        name: &'static str,
    ) -> Result<Self, Error> {
        if context.is_null() {
            return Err(Error::Null(name));
        }
        Ok(JavaContext { env, context })
    }
}

/// Sets up the platform verifier for unpinned `https://`; `true` when it is in use from now
/// on (always on the host), `false` when the library keeps the bundled roots (Android: the
/// init failed; why is logged). The first call decides for the whole process.
pub(crate) fn platform_tls_init(context: JavaContext<'_, '_>) -> Result<bool, Error> {
    crate::logging::init();
    #[cfg(target_os = "android")]
    {
        if let Some(first) = sitar_client::platform_tls::android_init_outcome() {
            return Ok(first.is_ok());
        }
        let outcome = android::init(context.env, context.context);
        Ok(sitar_client::platform_tls::set_android_platform_verifier(outcome).is_ok())
    }
    #[cfg(not(target_os = "android"))]
    {
        let _ = context;
        Ok(true)
    }
}

#[cfg(target_os = "android")]
mod android {
    use jni::objects::{JClassLoader, JObject};
    use jni::{jni_sig, jni_str, Env};

    /// A class of the verifier's Kotlin component, which its Rust side loads by name.
    const VERIFIER_CLASS: &str = "org.rustls.platformverifier.CertificateVerifier";

    /// Checks that the Kotlin component is in the app, then initialises the verifier.
    pub(super) fn init(env: &mut Env<'_>, context: JObject<'_>) -> Result<(), String> {
        component_present(env, &context).map_err(|e| {
            format!(
                "the verifier's Kotlin component ({VERIFIER_CLASS}, the \
                 rustls:rustls-platform-verifier AAR) cannot be loaded through the app's \
                 Context ({}); add it to the app (android/README.md, \"HTTPS\")",
                describe(env, e)
            )
        })?;
        rustls_platform_verifier::android::init_with_env(env, context).map_err(|e| {
            format!(
                "rustls-platform-verifier's JNI init failed: {}",
                describe(env, e)
            )
        })
    }

    /// `context.getClassLoader().loadClass(VERIFIER_CLASS)`: the loader the verifier uses.
    fn component_present(env: &mut Env<'_>, context: &JObject<'_>) -> jni::errors::Result<()> {
        let loader = env
            .call_method(
                context,
                jni_str!("getClassLoader"),
                jni_sig!("()Ljava/lang/ClassLoader;"),
                &[],
            )?
            .l()?;
        let loader = env.cast_local::<JClassLoader<'_>>(loader)?;
        let name = env.new_string(VERIFIER_CLASS)?;
        loader.load_class(env, name)?;
        Ok(())
    }

    /// The error, with a pending Java exception (a `ClassNotFoundException`, or a
    /// `NoSuchMethodError` for an argument that is no `Context`) caught and cleared, so
    /// that the caller gets an answer instead of that exception.
    fn describe(env: &Env<'_>, e: jni::errors::Error) -> String {
        match env.exception_catch() {
            Err(jni::errors::Error::CaughtJavaException { name, msg, .. }) => {
                format!("{name}: {msg}")
            }
            _ => e.to_string(),
        }
    }
}
