//! `exports!`: one declaration per export, from which the C entry point, the JNI entry point
//! and their descriptors ([`crate::descriptors`], for the generated headers and `Native.kt`) are
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
//! | `f64` | `double` | `Double` |
//! | `Fill<T>` (a [`crate::bridge::Fill`]: the array output written in place, no allocation; C only, declare it last) | `T *name, size_t capacity, size_t *out_len` (the array convention) | — |
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

//!
//! How the macro is built: each export walks its parameters once per bridge (`@params`),
//! one `name: kind` at a time. A kind is one `@kind` rule per bridge, which says only what
//! that kind adds — its parameters of the entry point, its conversion to what the safe
//! function takes, the argument of the call (and for JNI its Kotlin parameters) — and hands
//! them to `@push`, which appends them and walks on. A C output is one `@c_emit` rule: its
//! out-parameters and what it does with the result; `@c_fn` writes the guarded function and
//! `@decl` every descriptor. Adding a parameter kind is one `@kind` rule per bridge.

macro_rules! exports {
    ($(
        $(#[doc = $doc:literal])*
        $(#[cfg(feature = $feature:literal)])?
        fn $name:ident ( $($params:tt)* ) $(-> $ret:ty)?
            => $(c $cname:ident $couts:tt)? $(jni $jname:ident)? ;
    )*) => {
        $(
            $crate::exports_macro::exports!(@c [$(#[doc = $doc])*] [$($feature)?] $name
                [$($ret)?] [$($params)*] $(c $cname $couts)?);
            $crate::exports_macro::exports!(@jni [$(#[doc = $doc])*] [$($feature)?] $name
                [$($ret)?] [$($params)*] $(jni $jname)?);
        )*

        /// Every C entry point, for the header and the C# bindings.
        #[doc(hidden)]
        pub const C_EXPORTS: &[$crate::descriptors::Export] = &[$($( $cname::DECL, )?)*];

        /// Every JNI entry point, for `Native.kt`.
        #[doc(hidden)]
        pub const JNI_EXPORTS: &[$crate::descriptors::Export] = &[$($( $jname::DECL, )?)*];
    };

    // ---- Both bridges: the parameter walk ----------------------------------------------
    //
    // `@params $bridge [$head [acc]...] name: kind, …`: `$bridge` is `c` or `[jni $env]`
    // (`$env` is the closure's `Env`, named where the closure is written); the accumulators
    // are C: [signature] [conversions] [call arguments]; JNI: the same and [Kotlin parameters].

    (@params $bridge:tt $state:tt $n:ident : $($rest:tt)*) => {
        $crate::exports_macro::exports!(@split $bridge $state $n [] $($rest)*);
    };
    // The kind's tokens run up to the next comma.
    (@split $bridge:tt $state:tt $n:ident $kind:tt , $($rest:tt)*) => {
        $crate::exports_macro::exports!(@kind $bridge [$bridge $state [$($rest)*]] $n $kind);
    };
    (@split $bridge:tt $state:tt $n:ident $kind:tt) => {
        $crate::exports_macro::exports!(@kind $bridge [$bridge $state []] $n $kind);
    };
    (@split $bridge:tt $state:tt $n:ident [$($kind:tt)*] $t:tt $($rest:tt)*) => {
        $crate::exports_macro::exports!(@split $bridge $state $n [$($kind)* $t] $($rest)*);
    };
    // What a kind adds, one group per accumulator.
    (@push [$bridge:tt [$head:tt $([$($acc:tt)*])*] [$($rest:tt)*]] $([$($add:tt)*])*) => {
        $crate::exports_macro::exports!(@params $bridge [$head $([$($acc)* $($add)*])*] $($rest)*);
    };

    // ---- C ---------------------------------------------------------------------------

    (@c $docs:tt $feat:tt $name:ident $ret:tt $params:tt) => {};
    (@c $docs:tt $feat:tt $name:ident [] $params:tt c $cname:ident $couts:tt) => {
        $crate::exports_macro::exports!(@c $docs $feat $name [()] $params c $cname $couts);
    };
    (@c $docs:tt $feat:tt $name:ident [$ret:ty] [$($params:tt)*] c $cname:ident $couts:tt) => {
        $crate::exports_macro::exports!(@params c [[$docs $feat $name $cname $couts [$ret]] [] [] []]
            $($params)*);
    };

    // Parameter kinds: [C parameters] [conversion] [argument].
    (@kind c $k:tt $n:ident [SitarHandle]) => {
        $crate::exports_macro::exports!(@push $k [$n: SitarHandle,] [] [$n,]);
    };
    (@kind c $k:tt $n:ident [i64]) => {
        $crate::exports_macro::exports!(@push $k [$n: i64,] [] [$n,]);
    };
    (@kind c $k:tt $n:ident [i32]) => {
        $crate::exports_macro::exports!(@push $k [$n: i32,] [] [$n,]);
    };
    (@kind c $k:tt $n:ident [u32]) => {
        $crate::exports_macro::exports!(@push $k [$n: u32,] [] [$n,]);
    };
    (@kind c $k:tt $n:ident [f64]) => {
        $crate::exports_macro::exports!(@push $k [$n: f64,] [] [$n,]);
    };
    (@kind c $k:tt $n:ident [Fill < $t:ident >]) => {
        $crate::exports_macro::exports!(@push $k [$n: *mut $t, capacity: usize, out_len: *mut usize,]
            [let $n = $crate::c_api::fill_arg($n, capacity, out_len)?;] [$n,]);
    };
    (@kind c $k:tt $n:ident [&str]) => {
        $crate::exports_macro::exports!(@push $k [$n: *const c_char,]
            [let $n = $crate::c_api::text_arg($n, stringify!($n))?;] [$n,]);
    };
    (@kind c $k:tt $n:ident [Option<&str>]) => {
        $crate::exports_macro::exports!(@push $k [$n: *const c_char,]
            [let $n = $crate::c_api::optional_text_arg($n, stringify!($n))?;] [$n,]);
    };
    (@kind c $k:tt $n:ident [&Path]) => {
        $crate::exports_macro::exports!(@push $k [$n: *const c_char,]
            [let $n = ::std::path::Path::new($crate::c_api::text_arg($n, stringify!($n))?);]
            [$n,]);
    };
    (@kind c $k:tt $n:ident [&SitarPose]) => {
        $crate::exports_macro::exports!(@push $k [$n: *const SitarPose,]
            [let $n = $crate::c_api::arg($n, stringify!($n))?;] [$n,]);
    };
    (@kind c $k:tt $n:ident [&SitarIntrinsics]) => {
        $crate::exports_macro::exports!(@push $k [$n: *const SitarIntrinsics,]
            [let $n = $crate::c_api::arg($n, stringify!($n))?;] [$n,]);
    };
    (@kind c $k:tt $n:ident [DepthPointer]) => {
        $crate::exports_macro::exports!(@push $k
            [$n: *const u16, width: i32, height: i32, row_stride_bytes: i32,]
            [let $n = $crate::c_api::depth_arg($n, width, height, row_stride_bytes)?;] [$n,]);
    };
    (@kind c $k:tt $n:ident [LumaPointer]) => {
        $crate::exports_macro::exports!(@push $k
            [$n: *const u8, width: i32, height: i32, row_stride_bytes: i32,]
            [let $n = $crate::c_api::luma_arg($n, width, height, row_stride_bytes)?;] [$n,]);
    };

    // Every parameter walked: the call of the safe function, as a block.
    (@params c [[$docs:tt $feat:tt $name:ident $cname:ident $couts:tt [$ret:ty]]
        [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]]) => {
        $crate::exports_macro::exports!(@c_emit $couts [$ret] [$docs $feat $cname [$($sig)*]] $name
            { $($conv)* $crate::bridge::$name($($args)*)? });
    };

    // The entry point, by its outputs: [out-parameters] and the body of the guard, where
    // `$call` is the safe function's result (conversions and call, after the outputs'
    // checks).
    (@c_emit (static) [$ret:ty] $fn:tt $name:ident $call:block) => {
        // Cannot fail or panic: no guard, and the C string itself is returned.
        $crate::exports_macro::exports!(@c_item $fn [] [*const c_char] {
            let version: ::std::result::Result<$ret, _> = $crate::bridge::$name();
            version.map_or(c"".as_ptr(), ::std::ffi::CStr::as_ptr)
        });
    };
    (@c_emit () [$ret:ty] $fn:tt $name:ident $call:block) => {
        $crate::exports_macro::exports!(@c_fn $fn [] {
            // A result the C side does not take (e.g. the path written) is dropped.
            let _: $ret = $call;
            Ok(())
        });
    };
    (@c_emit (text) [$ret:ty] $fn:tt $name:ident $call:block) => {
        $crate::exports_macro::exports!(@c_fn $fn [buf: *mut c_char, cap: usize, out_len: *mut usize,] {
            $crate::c_api::check_array_out(buf, cap, out_len)?;
            let text: $ret = $call;
            $crate::c_api::copy_text(::core::convert::AsRef::<str>::as_ref(&text), buf, cap,
                out_len)
        });
    };
    (@c_emit (items: $item:ty) [$ret:ty] $fn:tt $name:ident $call:block) => {
        $crate::exports_macro::exports!(@c_fn $fn
            [out: *mut $item, capacity: usize, out_len: *mut usize,] {
            $crate::c_api::check_array_out(out, capacity, out_len)?;
            let items: $ret = $call;
            let items: &[$item] = &items;
            $crate::c_api::copy_items(items, out, capacity, out_len)
        });
    };
    (@c_emit ($o:ident : $ot:ty) [$ret:ty] $fn:tt $name:ident $call:block) => {
        $crate::exports_macro::exports!(@c_fn $fn [$o: *mut $ot,] {
            let $o = $crate::c_api::out($o, stringify!($o))?;
            let result: $ret = $call;
            *$o = ::core::convert::Into::into(result);
            Ok(())
        });
    };
    (@c_emit ($($o:ident : $ot:ty),+) [$ret:ty] $fn:tt $name:ident $call:block) => {
        $crate::exports_macro::exports!(@c_fn $fn [$($o: *mut $ot,)+] {
            $( let $o = $crate::c_api::out($o, stringify!($o))?; )+
            let result: $ret = $call;
            $crate::c_api::WriteOuts::write_outs(result, ($($o,)+));
            Ok(())
        });
    };

    // A guarded C entry point: the status of `$body`'s result, its message kept.
    (@c_fn $fn:tt $outs:tt $body:block) => {
        $crate::exports_macro::exports!(@c_item $fn $outs [i32] {
            $crate::guard::run_ffi_safe(|| $body)
        });
    };
    (@c_item [[$(#[doc = $doc:literal])*] [$($feature:literal)?] $cname:ident
        [$($p:ident : $t:ty,)*]] [$($o:ident : $ot:ty,)*] [$ret:ty] $body:block) => {
        $(#[doc = $doc])*
        $(#[cfg(feature = $feature)])?
        #[no_mangle]
        pub extern "C" fn $cname($($p: $t,)* $($o: $ot,)*) -> $ret $body

        $crate::exports_macro::exports!(@decl [$($doc)*] [$($feature)?] $cname
            [&[$( (stringify!($p), stringify!($t)), )* $( (stringify!($o), stringify!($ot)), )*]]
            [stringify!($ret)]);
    };

    // ---- JNI -------------------------------------------------------------------------

    (@jni $docs:tt $feat:tt $name:ident $ret:tt $params:tt) => {};
    (@jni $docs:tt $feat:tt $name:ident [] $params:tt jni $jname:ident) => {
        $crate::exports_macro::exports!(@jni $docs $feat $name [()] $params jni $jname);
    };
    (@jni $docs:tt $feat:tt $name:ident [$ret:ty] [$($params:tt)*] jni $jname:ident) => {
        $crate::exports_macro::exports!(@params [jni env] [[$docs $feat $name $jname [$ret]]
            [] [] [] []] $($params)*);
    };

    // Parameter kinds: [JNI parameters] [conversion] [argument] [Kotlin parameters].
    (@kind [jni $env:ident] $k:tt $n:ident [SitarHandle]) => {
        $crate::exports_macro::exports!(@push $k [$n: jlong,] [let $n = $n as u64;] [$n,]
            [(stringify!($n), "Long"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [i64]) => {
        $crate::exports_macro::exports!(@push $k [$n: jlong,] [] [$n,] [(stringify!($n), "Long"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [i32]) => {
        $crate::exports_macro::exports!(@push $k [$n: jint,] [] [$n,] [(stringify!($n), "Int"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [f64]) => {
        $crate::exports_macro::exports!(@push $k [$n: jdouble,] [] [$n,]
            [(stringify!($n), "Double"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [u32]) => {
        $crate::exports_macro::exports!(@push $k [$n: jint,]
            [let $n = $crate::jni_api::non_negative($n, stringify!($n))?;] [$n,]
            [(stringify!($n), "Int"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [&str]) => {
        $crate::exports_macro::exports!(@push $k [$n: JString<'l>,]
            [let $n = $crate::jni_api::string($env, &$n, stringify!($n))?;] [&$n,]
            [(stringify!($n), "String"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [Option<&str>]) => {
        $crate::exports_macro::exports!(@push $k [$n: JString<'l>,]
            [let $n = $crate::jni_api::optional_string($env, &$n, stringify!($n))?;]
            [$n.as_deref(),] [(stringify!($n), "String?"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [&Path]) => {
        $crate::exports_macro::exports!(@push $k [$n: JString<'l>,]
            [let $n = $crate::jni_api::path($env, &$n, stringify!($n))?;] [&$n,]
            [(stringify!($n), "String"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [&SitarPose]) => {
        $crate::exports_macro::exports!(@push $k
            [px: jdouble, py: jdouble, pz: jdouble, qx: jdouble, qy: jdouble, qz: jdouble,
                qw: jdouble,]
            [let $n = SitarPose { px, py, pz, qx, qy, qz, qw };]
            [&$n,]
            [("px", "Double"), ("py", "Double"), ("pz", "Double"), ("qx", "Double"),
                ("qy", "Double"), ("qz", "Double"), ("qw", "Double"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [&SitarIntrinsics]) => {
        $crate::exports_macro::exports!(@push $k
            [fx: jdouble, fy: jdouble, cx: jdouble, cy: jdouble,]
            [let $n = SitarIntrinsics { fx, fy, cx, cy };]
            [&$n,]
            [("fx", "Double"), ("fy", "Double"), ("cx", "Double"), ("cy", "Double"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [DirectBuffer]) => {
        $crate::exports_macro::exports!(@image_buffer $env $k $n depth_from_buffer);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [LumaBuffer]) => {
        $crate::exports_macro::exports!(@image_buffer $env $k $n luma_from_buffer);
    };
    // The elements are held (a JNI critical section) until the bridge call returns, so no
    // JNI call may follow: parameters after a `ShortArray` or a `ByteArray` must be ones
    // whose conversion calls no JNI (numbers, a pose, intrinsics).
    (@kind [jni $env:ident] $k:tt $n:ident [ShortArray]) => {
        $crate::exports_macro::exports!(@image_array $env $k $n ShortArray JShortArray u16 Depth
            DepthView);
    };
    // Holds the call's `Env` until the bridge call returns: declare it last.
    (@kind [jni $env:ident] $k:tt $n:ident [JavaContext]) => {
        $crate::exports_macro::exports!(@push $k [$n: JObject<'l>,]
            [let $n = $crate::android_tls::JavaContext::new($env, $n, stringify!($n))?;] [$n,]
            [(stringify!($n), "Any"),]);
    };
    (@kind [jni $env:ident] $k:tt $n:ident [ByteArray]) => {
        $crate::exports_macro::exports!(@image_array $env $k $n ByteArray JByteArray u8 Luma
            LumaView);
    };

    // An image in a direct `ByteBuffer` and its `width, height, rowStrideBytes`.
    (@image_buffer $env:ident $k:tt $n:ident $view:ident) => {
        $crate::exports_macro::exports!(@push $k
            [$n: JByteBuffer<'l>, width: jint, height: jint, row_stride_bytes: jint,]
            [let $n = $crate::jni_api::$view($env, &$n, width, height, row_stride_bytes)?;]
            [$n,]
            [(stringify!($n), "ByteBuffer"), ("width", "Int"), ("height", "Int"),
                ("row_stride_bytes", "Int"),]);
    };
    // An image in a Java array of signed `$array` read as `$sample`s, and its `width,
    // height, rowStrideBytes`; checked as an `ArrayImage::$image`, wrapped as a `$view`.
    (@image_array $env:ident $k:tt $n:ident $kotlin:ident $array:ident $sample:ident
        $image:ident $view:ident) => {
        $crate::exports_macro::exports!(@push $k
            [$n: $array<'l>, width: jint, height: jint, row_stride_bytes: jint,]
            [
                let needed = $crate::jni_api::image_array_len($env, &$n,
                    $crate::jni_api::ArrayImage::$image, width, height, row_stride_bytes)?;
                // SAFETY: read-only access; no JNI call happens while the critical
                // section is held (see the `ShortArray` kind).
                let elements = unsafe {
                    $n.get_elements_critical($env, ::jni::elements::ReleaseMode::NoCopyBack)?
                };
                // SAFETY: a signed and an unsigned integer of one width have the same size
                // and alignment; the array holds at least `needed` elements.
                let samples = unsafe {
                    ::std::slice::from_raw_parts(elements.as_ptr().cast::<$sample>(), needed)
                };
                let $n = $crate::bridge::$view::new(samples, width, height, row_stride_bytes)?;
            ]
            [$n,]
            [(stringify!($n), stringify!($kotlin)), ("width", "Int"), ("height", "Int"),
                ("row_stride_bytes", "Int"),]);
    };

    // Every parameter walked.
    (@params [jni $env:ident] [[[$(#[doc = $doc:literal])*] [$($feature:literal)?]
        $name:ident $jname:ident [$ret:ty]] [$($sig:tt)*] [$($conv:tt)*] [$($args:tt)*]
        [$($kt:tt)*]]) => {
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

        $crate::exports_macro::exports!(@decl [$($doc)*] [$($feature)?] $jname [&[$($kt)*]]
            [<$ret as $crate::jni_api::IntoJava<'static>>::KOTLIN]);
    };

    // ---- Both bridges: the descriptor --------------------------------------------------

    (@decl [$($doc:literal)*] [$($feature:literal)?] $export:ident [$params:expr]
        [$returns:expr]) => {
        #[doc(hidden)]
        #[allow(non_snake_case)]
        pub(crate) mod $export {
            #[allow(unused_imports)]
            use super::*;
            pub(crate) const DECL: $crate::descriptors::Export = $crate::descriptors::Export {
                name: stringify!($export),
                doc: concat!($($doc, "\n",)*),
                params: $params,
                returns: $returns,
                feature: $crate::exports_macro::exports!(@feature $($feature)?),
            };
        }
    };

    (@feature) => { None };
    (@feature $feature:literal) => { Some($feature) };
}

pub(crate) use exports;
