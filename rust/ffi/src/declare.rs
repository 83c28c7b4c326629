//! `exports!`: one declaration per export, from which the C entry point, the JNI entry point
//! and their descriptors ([`crate::decl`], for the generated headers and `Native.kt`) are
//! made. The pattern is libsignal's `bridge_fn`: the export is a safe Rust function
//! returning `Result<_, Error>` (in `bridge.rs`); the declaration says how each bridge
//! reaches it.
//!
//! ```text
//! /// Doc comment (header and rustdoc).
//! #[cfg(feature = "testing")]                       // optional
//! fn session_frame(h: SitarHandle, t_ns: i64, pose: &SitarPose) -> u32
//!     => c sitar_session_frame(out_flags: u32) jni sessionFrame;
//! ```
//!
//! calls `bridge::session_frame(h, t_ns, pose)` from
//! `int32_t sitar_session_frame(SitarHandle h, int64_t t_ns, const SitarPose *pose,
//! uint32_t *out_flags)` and from `Java_io_github_sitar_Native_sessionFrame(…, long h,
//! long tNs, double px, …, double qw) -> int`. Either bridge may be left out.
//!
//! Parameters (what the safe function takes ← C parameters | JNI parameters):
//!
//! | declared | C | JNI (Kotlin) |
//! |---|---|---|
//! | `SitarHandle`, `i64` | the same | `Long` |
//! | `i32` | `int32_t` | `Int` |
//! | `u32` | `uint32_t` | `Int`, negative → `INVALID_ARGUMENT` |
//! | `&str`, `&Path` | `const char *` (NULL → `SITAR_ERR_NULL`, bad UTF-8 → `INVALID_ARGUMENT`) | `String` |
//! | `Option<&str>` | `const char *`, NULL = `None` | `String?` |
//! | `&SitarPose` | `const SitarPose *` | `px, py, pz, qx, qy, qz, qw: Double` |
//! | `&SitarIntrinsics` | `const SitarIntrinsics *` | `fx, fy, cx, cy: Double` |
//! | `DepthPointer` (a `DepthView`) | `const uint16_t *name, int32_t width, height, row_stride_bytes` | — |
//! | `DirectBuffer` (a `DepthView`) | — | `name: ByteBuffer` (direct), `width, height, rowStrideBytes: Int` |
//! | `ShortArray` (a `DepthView`) | — | `name: ShortArray`, `width, height, rowStrideBytes: Int` |
//! | `LumaPointer` (a `LumaView`) | `const uint8_t *name, int32_t width, height, row_stride_bytes` | — |
//! | `LumaBuffer` (a `LumaView`) | — | `name: ByteBuffer` (direct), `width, height, rowStrideBytes: Int` |
//! | `ByteArray` (a `LumaView`) | — | `name: ByteArray`, `width, height, rowStrideBytes: Int` |
//! | `JavaContext` (the app's `Context`, with the call's `Env`; last parameter) | — | `name: Any` (null → `NULL`) |
//!
//! C outputs, in the parentheses after the C name (every pointer is checked before the call):
//! `()` none (a result is dropped); `(name: T)` writes `*name` (via `Into`); `(a: A, b: B, …)`
//! hands the result [`crate::c_api::WriteOuts`]; `(items: T)` the array convention
//! (`T *out, size_t capacity, size_t *out_len`); `(text)` the text convention (`char *buf,
//! size_t cap, size_t *out_len`); `(static)` returns the `&'static CStr` itself (for a
//! function that cannot fail or panic, so it needs no guard).
//! JNI returns the result through [`crate::jni_api::IntoJava`] (structs as flat `double[]`,
//! `flat.rs`). Errors: C returns the status and keeps the message as the thread's last
//! error ([`crate::guard::run_ffi_safe`]); JNI throws `SitarException` and returns 0/null
//! ([`crate::jni_api::run`]).

macro_rules! exports {
    ($(
        $(#[doc = $doc:literal])*
        $(#[cfg(feature = $feature:literal)])?
        fn $name:ident ( $($params:tt)* ) $(-> $ret:ty)?
            => $(c $cname:ident $couts:tt)? $(jni $jname:ident)? ;
    )*) => {
        $(
            $crate::declare::exports!(@c [$(#[doc = $doc])*] [$($feature)?] $name
                [$($ret)?] [$($params)*] $(c $cname $couts)?);
            $crate::declare::exports!(@jni [$(#[doc = $doc])*] [$($feature)?] $name
                [$($ret)?] [$($params)*] $(jni $jname)?);
        )*

        /// Every C entry point, for the header and the C# bindings.
        #[doc(hidden)]
        pub const C_EXPORTS: &[$crate::decl::Export] = &[$($( $cname::DECL, )?)*];

        /// Every JNI entry point, for `Native.kt`.
        #[doc(hidden)]
        pub const JNI_EXPORTS: &[$crate::decl::Export] = &[$($( $jname::DECL, )?)*];
    };

    // ---- C ---------------------------------------------------------------------------

    (@c $docs:tt $feat:tt $name:ident $ret:tt $params:tt) => {};
    (@c $docs:tt $feat:tt $name:ident [] $params:tt c $cname:ident $couts:tt) => {
        $crate::declare::exports!(@c $docs $feat $name [()] $params c $cname $couts);
    };
    (@c $docs:tt $feat:tt $name:ident [$ret:ty] [$($params:tt)*] c $cname:ident $couts:tt) => {
        $crate::declare::exports!(@c_param [$docs $feat $name $cname $couts [$ret]] [] [] []
            $($params)*);
    };

    // One parameter at a time: [signature] [conversions] [call arguments].
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : SitarHandle $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: SitarHandle,] [$($conv)*]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : i64 $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: i64,] [$($conv)*]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : i32 $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: i32,] [$($conv)*]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : u32 $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: u32,] [$($conv)*]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : &str $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: *const c_char,]
            [$($conv)* let $n = $crate::c_api::text_arg($n, stringify!($n))?;]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : Option<&str> $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: *const c_char,]
            [$($conv)* let $n = $crate::c_api::optional_text_arg($n, stringify!($n))?;]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : &Path $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: *const c_char,]
            [$($conv)* let $n = ::std::path::Path::new(
                $crate::c_api::text_arg($n, stringify!($n))?);]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : &SitarPose $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: *const SitarPose,]
            [$($conv)* let $n = $crate::c_api::arg($n, stringify!($n))?;]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : &SitarIntrinsics $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head [$($sig)* $n: *const SitarIntrinsics,]
            [$($conv)* let $n = $crate::c_api::arg($n, stringify!($n))?;]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : DepthPointer $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head
            [$($sig)* $n: *const u16, width: i32, height: i32, row_stride_bytes: i32,]
            [$($conv)* let $n = $crate::c_api::depth_arg($n, width, height, row_stride_bytes)?;]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param $head:tt [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        $n:ident : LumaPointer $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@c_param $head
            [$($sig)* $n: *const u8, width: i32, height: i32, row_stride_bytes: i32,]
            [$($conv)* let $n = $crate::c_api::luma_arg($n, width, height, row_stride_bytes)?;]
            [$($args)* $n,] $($($rest)*)?);
    };
    (@c_param [$docs:tt $feat:tt $name:ident $cname:ident $couts:tt $ret:tt] $sig:tt
        $conv:tt $args:tt) => {
        $crate::declare::exports!(@c_emit $docs $feat $name $cname $couts $ret $sig $conv
            $args);
    };

    // The entry point, by its outputs.
    (@c_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $cname:ident
        (static) [$ret:ty] [] [] []) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname() -> *const c_char {
            let version: ::std::result::Result<$ret, _> = $crate::bridge::$name();
            version.map_or(c"".as_ptr(), ::std::ffi::CStr::as_ptr)
        }
        $crate::declare::exports!(@c_decl [$($doc)*] [$($feature)?] $cname [] [*const c_char]);
    };
    (@c_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $cname:ident
        () [$ret:ty] [$($p:ident : $t:ty,)*] [$($conv:tt)*]
        [$($args:tt)*]) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname($($p: $t),*) -> i32 {
            $crate::guard::run_ffi_safe(|| {
                $($conv)*
                // A result the C side does not take (e.g. the path written) is dropped.
                let _: $ret = $crate::bridge::$name($($args)*)?;
                Ok(())
            })
        }
        $crate::declare::exports!(@c_decl [$($doc)*] [$($feature)?] $cname [$($p: $t,)*] [i32]);
    };
    (@c_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $cname:ident
        (text) [$ret:ty] [$($p:ident : $t:ty,)*] [$($conv:tt)*]
        [$($args:tt)*]) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname($($p: $t,)* buf: *mut c_char, cap: usize, out_len: *mut usize)
            -> i32 {
            $crate::guard::run_ffi_safe(|| {
                $crate::c_api::check_array_out(buf, cap, out_len)?;
                $($conv)*
                let text: $ret = $crate::bridge::$name($($args)*)?;
                $crate::c_api::copy_text(::core::convert::AsRef::<str>::as_ref(&text), buf, cap,
                    out_len)
            })
        }
        $crate::declare::exports!(@c_decl [$($doc)*] [$($feature)?] $cname
            [$($p: $t,)* buf: *mut c_char, cap: usize, out_len: *mut usize,] [i32]);
    };
    (@c_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $cname:ident
        (items: $item:ty) [$ret:ty] [$($p:ident : $t:ty,)*] [$($conv:tt)*]
        [$($args:tt)*]) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname($($p: $t,)* out: *mut $item, capacity: usize,
            out_len: *mut usize) -> i32 {
            $crate::guard::run_ffi_safe(|| {
                $crate::c_api::check_array_out(out, capacity, out_len)?;
                $($conv)*
                let items: $ret = $crate::bridge::$name($($args)*)?;
                let items: &[$item] = &items;
                $crate::c_api::copy_items(items, out, capacity, out_len)
            })
        }
        $crate::declare::exports!(@c_decl [$($doc)*] [$($feature)?] $cname
            [$($p: $t,)* out: *mut $item, capacity: usize, out_len: *mut usize,] [i32]);
    };
    (@c_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $cname:ident
        ($o:ident : $ot:ty) [$ret:ty] [$($p:ident : $t:ty,)*] [$($conv:tt)*]
        [$($args:tt)*]) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname($($p: $t,)* $o: *mut $ot) -> i32 {
            $crate::guard::run_ffi_safe(|| {
                let $o = $crate::c_api::out($o, stringify!($o))?;
                $($conv)*
                let result: $ret = $crate::bridge::$name($($args)*)?;
                *$o = ::core::convert::Into::into(result);
                Ok(())
            })
        }
        $crate::declare::exports!(@c_decl [$($doc)*] [$($feature)?] $cname
            [$($p: $t,)* $o: *mut $ot,] [i32]);
    };
    (@c_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $cname:ident
        ($($o:ident : $ot:ty),+) [$ret:ty] [$($p:ident : $t:ty,)*] [$($conv:tt)*]
        [$($args:tt)*]) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname($($p: $t,)* $($o: *mut $ot),+) -> i32 {
            $crate::guard::run_ffi_safe(|| {
                $( let $o = $crate::c_api::out($o, stringify!($o))?; )+
                $($conv)*
                let result: $ret = $crate::bridge::$name($($args)*)?;
                $crate::c_api::WriteOuts::write_outs(result, ($($o,)+));
                Ok(())
            })
        }
        $crate::declare::exports!(@c_decl [$($doc)*] [$($feature)?] $cname
            [$($p: $t,)* $($o: *mut $ot,)+] [i32]);
    };

    (@c_decl [$($doc:literal)*] [$($feature:literal)?] $cname:ident [$($p:ident : $t:ty,)*]
        [$ret:ty]) => {
        #[doc(hidden)]
        pub(crate) mod $cname {
            pub(crate) const DECL: $crate::decl::Export = $crate::decl::Export {
                name: stringify!($cname),
                doc: concat!($($doc, "\n",)*),
                params: &[$( (stringify!($p), stringify!($t)), )*],
                returns: stringify!($ret),
                feature: $crate::declare::exports!(@feature $($feature)?),
            };
        }
    };

    (@feature) => { None };
    (@feature $feature:literal) => { Some($feature) };

    // ---- JNI -------------------------------------------------------------------------

    (@jni $docs:tt $feat:tt $name:ident $ret:tt $params:tt) => {};
    (@jni $docs:tt $feat:tt $name:ident [] $params:tt jni $jname:ident) => {
        $crate::declare::exports!(@jni $docs $feat $name [()] $params jni $jname);
    };
    (@jni $docs:tt $feat:tt $name:ident [$ret:ty] [$($params:tt)*] jni $jname:ident) => {
        $crate::declare::exports!(@jni_param [env $docs $feat $name $jname [$ret]]
            [] [] [] [] $($params)*);
    };

    // One parameter at a time: [signature] [conversions] [call arguments] [Kotlin
    // parameters]. `$env` is the closure's `Env`, named where the closure is written.
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : SitarHandle $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: jlong,]
            [$($conv)* let $n = $n as u64;] [$($args)* $n,]
            [$($kt)* (stringify!($n), "Long"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : i64 $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: jlong,]
            [$($conv)*] [$($args)* $n,] [$($kt)* (stringify!($n), "Long"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : i32 $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: jint,]
            [$($conv)*] [$($args)* $n,] [$($kt)* (stringify!($n), "Int"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : u32 $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: jint,]
            [$($conv)* let $n = $crate::jni_api::non_negative($n, stringify!($n))?;]
            [$($args)* $n,] [$($kt)* (stringify!($n), "Int"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : &str $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: JString<'l>,]
            [$($conv)* let $n = $crate::jni_api::string($env, &$n, stringify!($n))?;]
            [$($args)* &$n,] [$($kt)* (stringify!($n), "String"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : Option<&str> $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: JString<'l>,]
            [$($conv)* let $n = $crate::jni_api::optional_string($env, &$n, stringify!($n))?;]
            [$($args)* $n.as_deref(),] [$($kt)* (stringify!($n), "String?"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : &Path $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: JString<'l>,]
            [$($conv)* let $n = $crate::jni_api::path($env, &$n, stringify!($n))?;]
            [$($args)* &$n,] [$($kt)* (stringify!($n), "String"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : &SitarPose $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*]
            [$($sig)* px: jdouble, py: jdouble, pz: jdouble, qx: jdouble, qy: jdouble,
                qz: jdouble, qw: jdouble,]
            [$($conv)* let $n = SitarPose { px, py, pz, qx, qy, qz, qw };]
            [$($args)* &$n,]
            [$($kt)* ("px", "Double"), ("py", "Double"), ("pz", "Double"), ("qx", "Double"),
                ("qy", "Double"), ("qz", "Double"), ("qw", "Double"),]
            $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : &SitarIntrinsics $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*]
            [$($sig)* fx: jdouble, fy: jdouble, cx: jdouble, cy: jdouble,]
            [$($conv)* let $n = SitarIntrinsics { fx, fy, cx, cy };]
            [$($args)* &$n,]
            [$($kt)* ("fx", "Double"), ("fy", "Double"), ("cx", "Double"), ("cy", "Double"),]
            $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : DirectBuffer $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*]
            [$($sig)* $n: JByteBuffer<'l>, width: jint, height: jint, row_stride_bytes: jint,]
            [$($conv)* let $n = $crate::jni_api::depth_from_buffer(
                $env, &$n, width, height, row_stride_bytes)?;]
            [$($args)* $n,]
            [$($kt)* (stringify!($n), "ByteBuffer"), ("width", "Int"), ("height", "Int"),
                ("row_stride_bytes", "Int"),]
            $($($rest)*)?);
    };
    // The elements are held (a JNI critical section) until the bridge call returns, so no
    // JNI call may follow: parameters after a `ShortArray` must be ones whose conversion
    // calls no JNI (numbers, a pose, intrinsics).
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : ShortArray $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*]
            [$($sig)* $n: JShortArray<'l>, width: jint, height: jint, row_stride_bytes: jint,]
            [$($conv)*
                let needed = $crate::jni_api::depth_array_len(
                    $env, &$n, width, height, row_stride_bytes)?;
                // SAFETY: read-only access; no JNI call happens while the critical
                // section is held (see above).
                let elements = unsafe {
                    $n.get_elements_critical($env, ::jni::elements::ReleaseMode::NoCopyBack)?
                };
                // SAFETY: i16 and u16 have the same size and alignment; the array holds
                // at least `needed` elements.
                let samples = unsafe {
                    ::std::slice::from_raw_parts(elements.as_ptr().cast::<u16>(), needed)
                };
                let $n = $crate::bridge::DepthView::new(samples, width, height,
                    row_stride_bytes)?;]
            [$($args)* $n,]
            [$($kt)* (stringify!($n), "ShortArray"), ("width", "Int"), ("height", "Int"),
                ("row_stride_bytes", "Int"),]
            $($($rest)*)?);
    };
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : LumaBuffer $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*]
            [$($sig)* $n: JByteBuffer<'l>, width: jint, height: jint, row_stride_bytes: jint,]
            [$($conv)* let $n = $crate::jni_api::luma_from_buffer(
                $env, &$n, width, height, row_stride_bytes)?;]
            [$($args)* $n,]
            [$($kt)* (stringify!($n), "ByteBuffer"), ("width", "Int"), ("height", "Int"),
                ("row_stride_bytes", "Int"),]
            $($($rest)*)?);
    };
    // As `ShortArray`: the elements are held in a critical section until the call returns.
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : ByteArray $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*]
            [$($sig)* $n: JByteArray<'l>, width: jint, height: jint, row_stride_bytes: jint,]
            [$($conv)*
                let needed = $crate::jni_api::luma_array_len(
                    $env, &$n, width, height, row_stride_bytes)?;
                // SAFETY: read-only access; no JNI call happens while the critical
                // section is held (see `ShortArray`).
                let elements = unsafe {
                    $n.get_elements_critical($env, ::jni::elements::ReleaseMode::NoCopyBack)?
                };
                // SAFETY: i8 and u8 have the same size and alignment; the array holds
                // at least `needed` elements.
                let bytes = unsafe {
                    ::std::slice::from_raw_parts(elements.as_ptr().cast::<u8>(), needed)
                };
                let $n = $crate::bridge::LumaView::new(bytes, width, height,
                    row_stride_bytes)?;]
            [$($args)* $n,]
            [$($kt)* (stringify!($n), "ByteArray"), ("width", "Int"), ("height", "Int"),
                ("row_stride_bytes", "Int"),]
            $($($rest)*)?);
    };
    // Holds the call's `Env` until the bridge call returns: declare it last.
    (@jni_param [$env:ident $($head:tt)*] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*] $n:ident : JavaContext $(, $($rest:tt)*)?) => {
        $crate::declare::exports!(@jni_param [$env $($head)*] [$($sig)* $n: JObject<'l>,]
            [$($conv)* let $n = $crate::android_tls::JavaContext::new($env, $n, stringify!($n))?;]
            [$($args)* $n,] [$($kt)* (stringify!($n), "Any"),] $($($rest)*)?);
    };
    (@jni_param [$env:ident $docs:tt $feat:tt $name:ident $jname:ident [$ret:ty]] $sig:tt
        $conv:tt $args:tt $kt:tt) => {
        $crate::declare::exports!(@jni_emit $docs $feat $name $jname [$ret] $env $sig $conv
            $args $kt);
    };

    (@jni_emit [$(#[doc = $doc:literal])*] [$($feature:literal)?] $name:ident $jname:ident
        [$ret:ty] $env:ident [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*] [$($kt:tt)*]) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[allow(non_snake_case)]
        #[export_name = concat!("Java_io_github_sitar_Native_", stringify!($jname))]
        extern "system" fn $jname<'l>(
            mut env: EnvUnowned<'l>,
            _class: JClass<'l>,
            $($sig)*
        ) -> <$ret as $crate::jni_api::IntoJava<'l>>::Java {
            $crate::jni_api::run(&mut env, |$env| {
                // The conversions' borrows (a critical array section) end with this block.
                let result: $ret = {
                    $($conv)*
                    $crate::bridge::$name($($args)*)?
                };
                $crate::jni_api::IntoJava::into_java(result, $env)
            })
        }

        #[doc(hidden)]
        #[allow(non_snake_case)]
        pub(crate) mod $jname {
            #[allow(unused_imports)]
            use super::*;
            pub(crate) const DECL: $crate::decl::Export = $crate::decl::Export {
                name: stringify!($jname),
                doc: concat!($($doc, "\n",)*),
                params: &[$($kt)*],
                returns: <$ret as $crate::jni_api::IntoJava<'static>>::KOTLIN,
                feature: $crate::declare::exports!(@feature $($feature)?),
            };
        }
    };
}

pub(crate) use exports;
