//! What the declarations say about each export, as data: the C signatures, the Kotlin
//! signatures of the JNI entry points, the flat array layouts and the C enums. The generated
//! glue (`include/sitar.h`, `NativeMethods.g.cs`, `Native.kt`, `Layouts.kt` and the status
//! enums of Kotlin and C#) is written from these tables by `tests/generated_bindings.rs`,
//! so it cannot drift from the entry points the same declarations compile to.
//!
//! Not a stable API: only the generator reads it.

/// One entry point: a C function (`sitar_…`) or a JNI method of `io.github.sitar.Native`
/// (`Java_io_github_sitar_Native_<name>`).
#[derive(Debug, Clone, Copy)]
pub struct Export {
    /// The C name, or the Kotlin method name.
    pub name: &'static str,
    /// The doc comment, one line per line.
    pub doc: &'static str,
    /// Parameters: name (snake_case) and type — the Rust type as written for C
    /// (`*const SitarPose`), the Kotlin type for JNI (`Double`).
    pub params: &'static [(&'static str, &'static str)],
    /// The return type: Rust for C (`i32`, or `*const c_char` for the version), Kotlin for
    /// JNI (`Unit` for none).
    pub returns: &'static str,
    /// The cargo feature it needs, if any.
    pub feature: Option<&'static str>,
}

/// The layout of a struct flattened into a JNI `double[]`.
#[derive(Debug, Clone, Copy)]
pub struct FlatLayout {
    /// The Kotlin name of the layout object, without `Layout` (e.g. `Summary`).
    pub kotlin: &'static str,
    /// The Rust struct.
    pub rust: &'static str,
    /// Fields in order: name and number of doubles (1, or a nested layout's size).
    pub fields: &'static [(&'static str, usize)],
}

/// A `#[repr(i32)]` C enum.
#[derive(Debug, Clone, Copy)]
pub struct CEnum {
    /// The C name.
    pub name: &'static str,
    /// The Kotlin enum class it becomes.
    pub kotlin: &'static str,
    /// The C# enum it becomes.
    pub csharp: &'static str,
    /// The doc comment.
    pub doc: &'static str,
    /// Variants: C name, value, doc.
    pub variants: &'static [(&'static str, i32, &'static str)],
}

/// Defines a `#[repr(i32)]` C enum and its [`CEnum`] descriptor (`Name::DECL`), with the
/// names of the Kotlin and C# enums generated from it.
macro_rules! c_enum {
    (
        $(#[doc = $doc:literal])*
        pub enum $name:ident as kotlin $kotlin:ident, csharp $csharp:ident {
            $( $(#[doc = $vdoc:literal])* $variant:ident = $value:literal, )*
        }
    ) => {
        $(#[doc = $doc])*
        #[repr(i32)]
        #[allow(non_camel_case_types)]
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $name {
            $( $(#[doc = $vdoc])* $variant = $value, )*
        }

        impl $name {
            /// What the generator needs to know of this enum.
            #[doc(hidden)]
            pub const DECL: $crate::descriptors::CEnum = $crate::descriptors::CEnum {
                name: stringify!($name),
                kotlin: stringify!($kotlin),
                csharp: stringify!($csharp),
                doc: concat!($($doc, "\n",)*),
                variants: &[$( (
                    stringify!($variant),
                    $name::$variant as i32,
                    concat!($($vdoc, "\n",)*),
                ), )*],
            };
        }
    };
}

pub(crate) use c_enum;
