//! What the JNI entry points (`Java_io_github_sitar_Native_*`, generated from
//! `exports.rs`) are made of: the error policy that throws
//! `io.github.sitar.SitarException(code, message)` and returns 0 / null, argument
//! conversions, and [`IntoJava`] for results. Structs travel as flat `double[]`
//! (`flat.rs`), so native code creates no Kotlin objects except strings, arrays and the
//! exception.

use std::ffi::CStr;
use std::path::PathBuf;

use jni::errors::ErrorPolicy;
use jni::objects::{
    JByteArray, JByteBuffer, JDoubleArray, JPrimitiveArray, JString, JThrowable, TypeArray,
};
use jni::sys::{jboolean, jint, jlong};
use jni::{jni_sig, jni_str, Env, EnvUnowned, JValue};

use crate::bridge::DepthView;
use crate::error::Error;
use crate::guard::{panic_message, record};

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

/// The guard of every JNI entry point: runs `f` with the `Env`, catching panics; an error or
/// a panic becomes a thrown `SitarException` (and the thread's last error) and the default
/// value is returned.
pub(crate) fn run<'l, T: Default + 'l>(
    env: &mut EnvUnowned<'l>,
    f: impl FnOnce(&mut Env<'l>) -> Result<T, Error>,
) -> T {
    env.with_env(f).resolve::<ThrowSitarException>()
}

/// A non-null Java string.
pub(crate) fn string(env: &Env<'_>, s: &JString<'_>, name: &'static str) -> Result<String, Error> {
    if s.is_null() {
        return Err(Error::Null(name));
    }
    Ok(s.try_to_string(env)?)
}

/// A Java string that may be null.
pub(crate) fn optional_string(
    env: &Env<'_>,
    s: &JString<'_>,
    name: &'static str,
) -> Result<Option<String>, Error> {
    if s.is_null() {
        Ok(None)
    } else {
        string(env, s, name).map(Some)
    }
}

/// A Java path string.
pub(crate) fn path(env: &Env<'_>, s: &JString<'_>, name: &'static str) -> Result<PathBuf, Error> {
    string(env, s, name).map(PathBuf::from)
}

/// A Kotlin `Int` that must not be negative.
pub(crate) fn non_negative(v: jint, name: &'static str) -> Result<u32, Error> {
    u32::try_from(v).map_err(|_| Error::invalid(name, format!("{v} is negative")))
}

pub(crate) fn doubles<'l>(env: &mut Env<'l>, values: &[f64]) -> Result<JDoubleArray<'l>, Error> {
    let array = env.new_double_array(values.len())?;
    array.set_region(env, 0, values)?;
    Ok(array)
}

/// The depth image in a *direct* `ByteBuffer` (16-bit samples, native byte order).
pub(crate) fn depth_from_buffer<'a>(
    env: &mut Env<'_>,
    buffer: &JByteBuffer<'_>,
    width: jint,
    height: jint,
    row_stride_bytes: jint,
) -> Result<DepthView<'a>, Error> {
    if buffer.is_null() {
        return Err(Error::Null("buffer"));
    }
    let address = env
        .get_direct_buffer_address(buffer)
        .map_err(|_| Error::invalid("buffer", "the depth ByteBuffer must be direct"))?;
    let capacity = env.get_direct_buffer_capacity(buffer)?;
    let len = crate::bridge::depth_len(width, height, row_stride_bytes)?;
    if capacity < len * 2 {
        return Err(Error::invalid(
            "buffer",
            format!(
                "{capacity} bytes; a {width}x{height} image with row stride {row_stride_bytes} needs {}",
                len * 2
            ),
        ));
    }
    if address.is_null() || !address.cast::<u16>().is_aligned() {
        return Err(Error::invalid(
            "buffer",
            "address is NULL or not 2-byte aligned",
        ));
    }
    // SAFETY: a direct buffer of at least the needed bytes, aligned for u16, alive for this
    // call (the Java caller holds it; the view does not outlive the entry point).
    let data = unsafe { std::slice::from_raw_parts(address.cast::<u16>().cast_const(), len) };
    DepthView::new(data, width, height, row_stride_bytes)
}

/// The camera's luminance plane in a *direct* `ByteBuffer` (ARCore's `Image.planes[0]`).
pub(crate) fn luma_from_buffer<'a>(
    env: &mut Env<'_>,
    buffer: &JByteBuffer<'_>,
    width: jint,
    height: jint,
    row_stride_bytes: jint,
) -> Result<crate::bridge::LumaView<'a>, Error> {
    if buffer.is_null() {
        return Err(Error::Null("luma"));
    }
    let address = env
        .get_direct_buffer_address(buffer)
        .map_err(|_| Error::invalid("luma", "the luminance ByteBuffer must be direct"))?;
    let capacity = env.get_direct_buffer_capacity(buffer)?;
    let len = crate::bridge::luma_len(width, height, row_stride_bytes)?;
    if capacity < len {
        return Err(Error::invalid(
            "luma",
            format!(
                "{capacity} bytes; a {width}x{height} plane with row stride {row_stride_bytes} needs {len}"
            ),
        ));
    }
    if address.is_null() {
        return Err(Error::invalid("luma", "buffer address is NULL"));
    }
    // SAFETY: a direct buffer of at least `len` bytes, alive for this JNI call.
    let data = unsafe { std::slice::from_raw_parts(address.cast_const(), len) };
    crate::bridge::LumaView::new(data, width, height, row_stride_bytes)
}

/// The image a Java array holds, for [`image_array_len`].
pub(crate) enum ArrayImage {
    /// A depth image in a `ShortArray` (parameter `data`).
    Depth,
    /// A luminance plane in a `ByteArray` (parameter `luma`).
    Luma,
}

/// Checks a Java array holding `image` and returns the number of elements it needs: not
/// null, a valid geometry, and at least that many elements.
pub(crate) fn image_array_len<T: TypeArray>(
    env: &Env<'_>,
    array: &JPrimitiveArray<'_, T>,
    image: ArrayImage,
    width: jint,
    height: jint,
    row_stride_bytes: jint,
) -> Result<usize, Error> {
    let name = match image {
        ArrayImage::Depth => "data",
        ArrayImage::Luma => "luma",
    };
    if array.is_null() {
        return Err(Error::Null(name));
    }
    let needed = match image {
        ArrayImage::Depth => crate::bridge::depth_len(width, height, row_stride_bytes)?,
        ArrayImage::Luma => crate::bridge::luma_len(width, height, row_stride_bytes)?,
    };
    let available = array.len(env)?;
    if available < needed {
        // Described only when refused: this check runs for every frame's image.
        let what = match image {
            ArrayImage::Depth => {
                format!("shorts; a {width}x{height} image with row stride {row_stride_bytes} bytes")
            }
            ArrayImage::Luma => {
                format!("bytes; a {width}x{height} plane with row stride {row_stride_bytes}")
            }
        };
        return Err(Error::invalid(
            name,
            format!("{available} {what} needs {needed}"),
        ));
    }
    Ok(needed)
}

/// How a bridge result reaches Kotlin: the JNI return type, its Kotlin spelling (for
/// `Native.kt`) and the conversion.
pub(crate) trait IntoJava<'l>: Sized {
    /// What the entry point returns.
    type Java: Default + 'l;
    /// The Kotlin type of the `external fun`.
    const KOTLIN: &'static str;
    /// Converts the result.
    fn into_java(self, env: &mut Env<'l>) -> Result<Self::Java, Error>;
}

macro_rules! into_java_as {
    ($($rust:ty => $java:ty, $kotlin:literal;)*) => {$(
        impl<'l> IntoJava<'l> for $rust {
            type Java = $java;
            const KOTLIN: &'static str = $kotlin;
            fn into_java(self, _env: &mut Env<'l>) -> Result<$java, Error> {
                // Handles and lengths fit a jlong; frame flags and classes fit a jint.
                Ok(self as $java)
            }
        }
    )*};
}

into_java_as! {
    u64 => jlong, "Long";
    usize => jlong, "Long";
    u32 => jint, "Int";
    i32 => jint, "Int";
}

impl<'l> IntoJava<'l> for () {
    type Java = ();
    const KOTLIN: &'static str = "Unit";
    fn into_java(self, _env: &mut Env<'l>) -> Result<(), Error> {
        Ok(())
    }
}

impl<'l> IntoJava<'l> for bool {
    type Java = jboolean;
    const KOTLIN: &'static str = "Boolean";
    fn into_java(self, _env: &mut Env<'l>) -> Result<jboolean, Error> {
        Ok(self)
    }
}

impl<'l> IntoJava<'l> for String {
    type Java = JString<'l>;
    const KOTLIN: &'static str = "String";
    fn into_java(self, env: &mut Env<'l>) -> Result<JString<'l>, Error> {
        Ok(env.new_string(self)?)
    }
}

impl<'l> IntoJava<'l> for &'static CStr {
    type Java = JString<'l>;
    const KOTLIN: &'static str = "String";
    fn into_java(self, env: &mut Env<'l>) -> Result<JString<'l>, Error> {
        Ok(env.new_string(self.to_string_lossy())?)
    }
}

impl<'l> IntoJava<'l> for Vec<u8> {
    type Java = JByteArray<'l>;
    const KOTLIN: &'static str = "ByteArray";
    fn into_java(self, env: &mut Env<'l>) -> Result<JByteArray<'l>, Error> {
        Ok(env.byte_array_from_slice(&self)?)
    }
}

impl<'l> IntoJava<'l> for PathBuf {
    type Java = JString<'l>;
    const KOTLIN: &'static str = "String";
    fn into_java(self, env: &mut Env<'l>) -> Result<JString<'l>, Error> {
        Ok(env.new_string(self.to_string_lossy())?)
    }
}
