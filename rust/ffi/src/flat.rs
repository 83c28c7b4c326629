//! Structs as flat `double[]` for JNI: one declaration per struct gives its field order, the
//! flattening, and the offsets `Layouts.kt` decodes with (`<Name>Layout.FIELD`, `SIZE`).
//! Lists are the items one after the other; the render plan is a header of counts, the
//! items, then the start and stop poses if present.

use jni::objects::JDoubleArray;
use jni::Env;

use crate::bridge::{PlanEnds, RenderPlanC, SitarBoundsAt, SitarErrorAt, SitarProvenance};
use crate::descriptors::FlatLayout;
use crate::error::Error;
use crate::jni_api::{doubles, IntoJava};
use crate::types::{
    SitarEvidence, SitarFrustum, SitarGuide, SitarJobProgress, SitarJoint, SitarMarker, SitarPose,
    SitarSegment, SitarSubtrajectoryResult, SitarSummary, SitarVenueCell,
};

/// A struct with a flat layout.
pub(crate) trait Flat {
    /// Doubles per value.
    const WIDTH: usize;
    /// Appends the value's doubles in layout order.
    fn push_to(&self, out: &mut Vec<f64>);
}

/// A field stored as one double.
trait FlatValue {
    fn to_f64(&self) -> f64;
}

macro_rules! flat_value {
    ($($t:ty),*) => {$(
        impl FlatValue for $t {
            fn to_f64(&self) -> f64 {
                // Counts and byte totals stay far below 2^53: exact.
                *self as f64
            }
        }
    )*};
}

flat_value!(f64, u32, i32, u64, usize);

impl FlatValue for bool {
    fn to_f64(&self) -> f64 {
        f64::from(u8::from(*self))
    }
}

macro_rules! flat_width {
    () => {
        1
    };
    ($nested:ty) => {
        <$nested as Flat>::WIDTH
    };
}

macro_rules! flat_push {
    ($value:expr, $out:ident) => {
        $out.push(FlatValue::to_f64(&$value))
    };
    ($value:expr, $out:ident, $nested:ty) => {
        Flat::push_to(&$value, $out)
    };
}

/// Declares the flat layout of each struct: `Rust as Kotlin { field, nested: Type, … }`.
macro_rules! flat_layouts {
    ($( $rust:ident as $kotlin:ident { $( $field:ident $(: $nested:ty)? ),* $(,)? } )*) => {
        $(
            impl Flat for $rust {
                const WIDTH: usize = 0 $( + flat_width!($($nested)?) )*;
                fn push_to(&self, out: &mut Vec<f64>) {
                    $( flat_push!(self.$field, out $(, $nested)?); )*
                }
            }

            impl<'l> IntoJava<'l> for $rust {
                type Java = JDoubleArray<'l>;
                const KOTLIN: &'static str = "DoubleArray";
                fn into_java(self, env: &mut Env<'l>) -> Result<JDoubleArray<'l>, Error> {
                    let mut v = Vec::with_capacity(Self::WIDTH);
                    self.push_to(&mut v);
                    doubles(env, &v)
                }
            }
        )*

        /// Every flat layout, for `Layouts.kt`.
        #[doc(hidden)]
        pub const FLAT_LAYOUTS: &[FlatLayout] = &[$(
            FlatLayout {
                kotlin: stringify!($kotlin),
                rust: stringify!($rust),
                fields: &[$( (stringify!($field), flat_width!($($nested)?)) ),*],
            },
        )*];
    };
}

/// The counts that open a flat render plan.
pub(crate) struct RenderPlanHeader {
    segments: usize,
    joints: usize,
    frustums: usize,
    has_start: bool,
    has_stop: bool,
}

flat_layouts! {
    SitarPose as Pose { px, py, pz, qx, qy, qz, qw }
    SitarSummary as Summary {
        frames, midpoints, subtrajectories, depth_samples, duration_s, length_m, mean_depth_m,
    }
    SitarErrorAt as ErrorAt { error_class, error_m }
    SitarBoundsAt as BoundsAt { present, lower_m, upper_m, raw_m }
    SitarProvenance as Provenance { source, target, runs, informative }
    SitarMarker as Marker {
        px, py, pz, qx, qy, qz, qw, nx, ny, nz, error_class, subtrajectory, error_m,
    }
    SitarSubtrajectoryResult as SubtrajectoryResult { error_m, subtrajectory, error_class }
    SitarEvidence as Evidence {
        subtrajectory, has_image, mean_brightness, contrast_std, laplacian_var, corners_per_10k,
        saturated_share, linear_speed_m_s, angular_speed_deg_s, depth_given, depth_valid,
        distance_m, depth_valid_share, causes, thumbnail_width, thumbnail_height,
    }
    SitarSegment as Segment { cx, cy, cz, qx, qy, qz, qw, length, subtrajectory, error_class }
    SitarJoint as Joint { px, py, pz, subtrajectory, error_class }
    SitarFrustum as Frustum { pose: SitarPose, subtrajectory, error_class }
    SitarGuide as Guide { on_screen, x_px, y_px, angle_rad, distance_m }
    SitarVenueCell as VenueCell { px, py, pz, kind, error_class, sessions, error_m }
    RenderPlanHeader as RenderPlan { segments, joints, frustums, has_start, has_stop }
    SitarJobProgress as UploadProgress {
        state, error_code, progress, eta_s, bytes_sent, bytes_total, trials_done, trials_total,
        results_revision, results_trials,
    }
}

fn push_all<T: Flat>(items: &[T], out: &mut Vec<f64>) {
    for item in items {
        item.push_to(out);
    }
}

impl<'l, T: Flat> IntoJava<'l> for Vec<T> {
    type Java = JDoubleArray<'l>;
    const KOTLIN: &'static str = "DoubleArray";
    fn into_java(self, env: &mut Env<'l>) -> Result<JDoubleArray<'l>, Error> {
        let mut v = Vec::with_capacity(self.len() * T::WIDTH);
        push_all(&self, &mut v);
        doubles(env, &v)
    }
}

/// `RenderPlanLayout` counts, the segments, joints and frustums, then the start and stop
/// poses that are present.
pub(crate) fn flatten_render_plan(plan: &RenderPlanC) -> Vec<f64> {
    let PlanEnds { start, stop } = plan.ends;
    let header = RenderPlanHeader {
        segments: plan.segments.len(),
        joints: plan.joints.len(),
        frustums: plan.frustums.len(),
        has_start: start.is_some(),
        has_stop: stop.is_some(),
    };
    let mut v = Vec::with_capacity(
        RenderPlanHeader::WIDTH
            + plan.segments.len() * SitarSegment::WIDTH
            + plan.joints.len() * SitarJoint::WIDTH
            + plan.frustums.len() * SitarFrustum::WIDTH
            + 2 * SitarPose::WIDTH,
    );
    header.push_to(&mut v);
    push_all(&plan.segments, &mut v);
    push_all(&plan.joints, &mut v);
    push_all(&plan.frustums, &mut v);
    for pose in start.iter().chain(stop.iter()) {
        pose.push_to(&mut v);
    }
    v
}

impl<'l> IntoJava<'l> for RenderPlanC {
    type Java = JDoubleArray<'l>;
    const KOTLIN: &'static str = "DoubleArray";
    fn into_java(self, env: &mut Env<'l>) -> Result<JDoubleArray<'l>, Error> {
        doubles(env, &flatten_render_plan(&self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(kotlin: &str) -> &'static FlatLayout {
        FLAT_LAYOUTS.iter().find(|l| l.kotlin == kotlin).unwrap()
    }

    #[test]
    fn widths_follow_the_fields_and_nest() {
        assert_eq!(SitarPose::WIDTH, 7);
        assert_eq!(SitarMarker::WIDTH, 13);
        assert_eq!(SitarFrustum::WIDTH, 9);
        assert_eq!(SitarJobProgress::WIDTH, 10);
        assert_eq!(SitarEvidence::WIDTH, 16);
        assert_eq!(SitarGuide::WIDTH, 5);
        assert_eq!(SitarVenueCell::WIDTH, 7);
        for l in FLAT_LAYOUTS {
            let width: usize = l.fields.iter().map(|f| f.1).sum();
            let rust = match l.kotlin {
                "Pose" => SitarPose::WIDTH,
                "Summary" => SitarSummary::WIDTH,
                "ErrorAt" => SitarErrorAt::WIDTH,
                "BoundsAt" => SitarBoundsAt::WIDTH,
                "Provenance" => SitarProvenance::WIDTH,
                "Marker" => SitarMarker::WIDTH,
                "SubtrajectoryResult" => SitarSubtrajectoryResult::WIDTH,
                "Segment" => SitarSegment::WIDTH,
                "Joint" => SitarJoint::WIDTH,
                "Frustum" => SitarFrustum::WIDTH,
                "RenderPlan" => RenderPlanHeader::WIDTH,
                "UploadProgress" => SitarJobProgress::WIDTH,
                "Evidence" => SitarEvidence::WIDTH,
                "Guide" => SitarGuide::WIDTH,
                "VenueCell" => SitarVenueCell::WIDTH,
                other => panic!("unknown layout {other}"),
            };
            assert_eq!(width, rust, "{}", l.kotlin);
        }
        assert_eq!(layout("Frustum").fields[0], ("pose", 7));
    }

    #[test]
    fn values_land_at_their_declared_offsets() {
        let m = SitarMarker {
            px: 1.0,
            nz: 2.0,
            error_class: 3,
            subtrajectory: 4,
            error_m: 0.5,
            ..SitarMarker::default()
        };
        let mut v = Vec::new();
        m.push_to(&mut v);
        let offset = |name: &str| {
            let fields = layout("Marker").fields;
            let i = fields.iter().position(|f| f.0 == name).unwrap();
            fields[..i].iter().map(|f| f.1).sum::<usize>()
        };
        assert_eq!(v.len(), 13);
        assert_eq!(v[offset("px")], 1.0);
        assert_eq!(v[offset("nz")], 2.0);
        assert_eq!(v[offset("error_class")], 3.0);
        assert_eq!(v[offset("subtrajectory")], 4.0);
        assert_eq!(v[offset("error_m")], 0.5);
    }

    #[test]
    fn a_render_plan_is_counts_items_then_the_present_ends() {
        let pose = |x: f64| SitarPose {
            px: x,
            qw: 1.0,
            ..SitarPose::default()
        };
        let plan = RenderPlanC {
            segments: vec![SitarSegment {
                length: 0.3,
                error_class: 2,
                ..SitarSegment::default()
            }],
            joints: vec![SitarJoint::default(); 2],
            frustums: vec![SitarFrustum {
                pose: pose(5.0),
                subtrajectory: 1,
                error_class: 3,
            }],
            ends: PlanEnds {
                start: None,
                stop: Some(pose(9.0)),
            },
        };
        let v = flatten_render_plan(&plan);
        assert_eq!(&v[..5], &[1.0, 2.0, 1.0, 0.0, 1.0]);
        assert_eq!(v.len(), 5 + 10 + 2 * 5 + 9 + 7);
        assert_eq!((v[5 + 7], v[5 + 9]), (0.3, 2.0));
        let frustum = 5 + 10 + 10;
        assert_eq!(
            (v[frustum], v[frustum + 7], v[frustum + 8]),
            (5.0, 1.0, 3.0)
        );
        assert_eq!(v[frustum + 9], 9.0, "only the stop pose follows");
    }
}
