//! Region selection: where to place exclamation points / warning signs.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::{Convention, ErrorClass, SessionConfig};

/// A marker on a surface the camera faced during a high-error sub-trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Surface point (world, session convention).
    pub position: DVec3,
    /// Warning-sign orientation: local +Y along the normal (see [`warning_sign_rotation`]).
    pub rotation: DQuat,
    /// Exclamation-point orientation: upright (identity).
    pub upright: DQuat,
    /// Unit surface normal (world), facing the camera.
    pub normal: DVec3,
    /// High if the candidate's value is ≥ `high_threshold_m` (`_deg`), else medium. From
    /// [`crate::Session::markers`] the value `classify_by` picks: the error, or the upper
    /// bound of a calibrated window.
    pub class: ErrorClass,
    /// The sub-trajectory the marker belongs to.
    pub subtrajectory: u32,
    /// That sub-trajectory's estimated error (the results' unit: metres, or degrees). From
    /// [`crate::Session::markers`] always the window's error, whichever value placed it.
    pub error_m: f64,
}

/// A sub-trajectory that could get a marker: its surface sample and error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarkerCandidate {
    /// Sub-trajectory index.
    pub subtrajectory: u32,
    /// Surface point (world).
    pub position: DVec3,
    /// Unit surface normal (world).
    pub normal: DVec3,
    /// The value the search and the class use (metres, or degrees): the estimated error, or
    /// with `classify_by` `"upper"` the window's upper bound.
    pub error_m: f64,
}

/// The warning-sign rotation for a surface normal, in `convention`.
///
/// In Unity terms it is `Quaternion.LookRotation(forward, normal)` with
/// `forward = normal × (normal × up)` (up = world +Y): local +Y is the normal, local +Z runs
/// down the surface. For a normal parallel to up (floor, ceiling) world +Z replaces up.
/// For `arcore` the result is the same physical orientation converted with the reflection
/// `S R S` (local +Y is still the normal; local −Z runs down the surface).
pub fn warning_sign_rotation(normal: DVec3, convention: Convention) -> DQuat {
    let n = convention
        .convert_vector(normal, Convention::Unity)
        .normalize_or_zero();
    if n == DVec3::ZERO {
        return DQuat::IDENTITY;
    }
    let mut reference = DVec3::Y;
    if n.cross(reference).length_squared() < 1e-12 {
        reference = DVec3::Z;
    }
    let z = n.cross(n.cross(reference)).normalize();
    // LookRotation(forward = z, upwards = n): x = up × z, y = z × x.
    let x = n.cross(z).normalize();
    let y = z.cross(x);
    let unity = DQuat::from_mat3(&DMat3::from_cols(x, y, z)).normalize();
    Convention::Unity.convert_rotation(unity, convention)
}

/// Spatial hash of accepted marker positions with cells twice the dedup radius, so a query
/// looks at the 2×2×2 cells that can hold a point within the radius.
struct SpatialHash {
    cell: f64,
    cells: HashMap<(i64, i64, i64), Vec<DVec3>, BuildHasherDefault<CellHasher>>,
    /// Every point, for a direct scan while there are few (cheaper than 8 lookups).
    points: Vec<DVec3>,
}

/// Up to this many points a query scans them directly instead of the cells.
const DIRECT_SCAN: usize = 8;

/// Cell coordinates are exact integers below 2^52 cells from the origin. Farther out (or
/// with a tiny radius) they are not, and the `i64` keys saturate, so a neighbour key would
/// overflow: a query there scans every point.
const EXACT_CELLS: f64 = 4_503_599_627_370_496.0;

/// A small multiplicative hasher for integer cell keys (std's SipHash is ~5× slower here).
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        // Only reached for non-integer keys; cell keys use write_i64.
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
}

impl SpatialHash {
    fn new(radius: f64) -> Self {
        // A zero radius still needs a positive cell; any size works for exact coincidence.
        let cell = if radius > 0.0 { 2.0 * radius } else { 1.0 };
        Self {
            cell,
            cells: HashMap::default(),
            points: Vec::new(),
        }
    }

    fn key(&self, p: DVec3) -> (i64, i64, i64) {
        let c = (p / self.cell).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    }

    fn insert(&mut self, p: DVec3) {
        self.cells.entry(self.key(p)).or_default().push(p);
        self.points.push(p);
    }

    /// Whether an inserted point lies within `radius` (inclusive) of `p`.
    fn any_within(&self, p: DVec3, radius: f64) -> bool {
        let r2 = radius * radius;
        let scaled = p / self.cell;
        if self.points.len() <= DIRECT_SCAN || scaled.abs().max_element() >= EXACT_CELLS {
            return self.points.iter().any(|q| q.distance_squared(p) <= r2);
        }
        let base = scaled.floor();
        // Per axis, the neighbour cell on the side p is closer to (cell = 2 × radius).
        let side = |f: f64, b: f64| if f - b < 0.5 { -1 } else { 1 };
        let (bx, by, bz) = (base.x as i64, base.y as i64, base.z as i64);
        let (sx, sy, sz) = (
            side(scaled.x, base.x),
            side(scaled.y, base.y),
            side(scaled.z, base.z),
        );
        for dx in [0, sx] {
            for dy in [0, sy] {
                for dz in [0, sz] {
                    if let Some(points) = self.cells.get(&(bx + dx, by + dy, bz + dz))
                        && points.iter().any(|q| q.distance_squared(p) <= r2)
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Selects marker regions as the original app did: for each threshold of
/// `config.thresholds_m` (`thresholds_deg` for `angle_deg`) in order, walk the candidates in time order and accept one whose
/// error is ≥ the threshold and which lies strictly farther than `dedup_radius_m` from every
/// accepted marker, until `max_regions` are placed. Candidates with a non-finite position,
/// normal or error are skipped. Markers come out in acceptance order.
pub fn select_markers(candidates: &[MarkerCandidate], config: &SessionConfig) -> Vec<Marker> {
    let max = config.max_regions;
    let radius = config.dedup_radius_m;
    let mut markers = Vec::with_capacity(max.min(candidates.len()));
    if max == 0 {
        return markers;
    }
    let mut hash = SpatialHash::new(radius);
    // Once too close to an accepted marker, always too close: the accepted set only grows.
    let mut done = vec![false; candidates.len()];
    for &threshold in config.marker_thresholds() {
        for (i, c) in candidates.iter().enumerate() {
            // NaN errors fail the comparison and are never taken.
            if done[i] || c.error_m.partial_cmp(&threshold).is_none_or(|o| o.is_lt()) {
                continue;
            }
            done[i] = true;
            if !(c.position.is_finite() && c.normal.is_finite() && c.error_m.is_finite()) {
                continue;
            }
            if hash.any_within(c.position, radius) {
                continue;
            }
            hash.insert(c.position);
            // Markers are never low: the original app coloured them medium or high.
            let class = config
                .class_thresholds()
                .classify(c.error_m)
                .max(ErrorClass::Medium);
            markers.push(Marker {
                position: c.position,
                rotation: warning_sign_rotation(c.normal, config.convention),
                upright: DQuat::IDENTITY,
                normal: c.normal,
                class,
                subtrajectory: c.subtrajectory,
                error_m: c.error_m,
            });
            if markers.len() >= max {
                return markers;
            }
        }
    }
    markers
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn cand(k: u32, x: f64, error_m: f64) -> MarkerCandidate {
        MarkerCandidate {
            subtrajectory: k,
            position: DVec3::new(x, 1.0, 2.0),
            normal: DVec3::NEG_Z,
            error_m,
        }
    }

    #[test]
    fn cascade_time_order_and_dedup() {
        let c = [
            cand(0, -0.4, 0.03), // found at the 2 cm level
            cand(1, 0.2, 0.12),  // first ≥ 10 cm
            cand(2, 0.5, 0.11),  // exactly 0.3 m from #1: rejected
            cand(3, 0.71, 0.15), // 0.51 m from #1: accepted at 10 cm
            cand(4, 3.0, 0.06),  // 5 cm level
            cand(5, 9.0, 0.005), // below every threshold
        ];
        let m = select_markers(&c, &SessionConfig::default());
        let ks: Vec<u32> = m.iter().map(|m| m.subtrajectory).collect();
        assert_eq!(ks, vec![1, 3, 4]);
        assert_eq!(m[0].class, ErrorClass::High);
        assert_eq!(m[2].class, ErrorClass::Medium);
        assert_eq!(m[0].upright, DQuat::IDENTITY);
        let mut config = SessionConfig {
            max_regions: 10,
            ..SessionConfig::default()
        };
        let ks: Vec<u32> = select_markers(&c, &config)
            .iter()
            .map(|m| m.subtrajectory)
            .collect();
        assert_eq!(ks, vec![1, 3, 4, 0]);
        // Exactly at the radius is "within": a new marker must be strictly farther.
        config.dedup_radius_m = 0.5;
        let ks: Vec<u32> = select_markers(
            &[
                cand(0, 0.0, 0.2),
                cand(1, 0.5, 0.2),
                cand(2, 0.5000001, 0.2),
            ],
            &config,
        )
        .iter()
        .map(|m| m.subtrajectory)
        .collect();
        assert_eq!(ks, vec![0, 2]);
    }

    #[test]
    fn warning_sign_on_a_wall_and_on_the_floor() {
        for conv in [Convention::Unity, Convention::Arcore] {
            for n in [
                DVec3::NEG_Z,
                DVec3::new(1.0, 0.3, -0.2).normalize(),
                DVec3::Y,
                DVec3::NEG_Y,
            ] {
                let q = warning_sign_rotation(n, conv);
                assert!((q * DVec3::Y - n).length() < 1e-12, "{conv:?} {n}");
            }
        }
        // Unity wall facing −Z: local +Z runs straight down the wall.
        let q = warning_sign_rotation(DVec3::NEG_Z, Convention::Unity);
        assert!((q * DVec3::Z - DVec3::NEG_Y).length() < 1e-12);
        assert!((q * DVec3::X - DVec3::NEG_X).length() < 1e-12);
    }

    #[test]
    fn far_out_positions_and_tiny_radii_do_not_overflow_the_cell_keys() {
        // Found by fuzzing (fuzz target `markers`): with more than DIRECT_SCAN accepted
        // markers, a candidate whose cell coordinate saturates the i64 key made the neighbour
        // key `i64::MIN - 1` overflow (a panic in debug builds).
        let mut c: Vec<MarkerCandidate> = (0..9).map(|k| cand(k, 10.0 * k as f64, 0.2)).collect();
        c.push(cand(9, -8.2e62, 0.2));
        c.push(cand(10, -8.2e62, 0.2)); // the same point: deduplicated
        c.push(cand(11, 1e300, 0.2));
        let config = SessionConfig {
            max_regions: 20,
            ..SessionConfig::default()
        };
        let ks: Vec<u32> = select_markers(&c, &config)
            .iter()
            .map(|m| m.subtrajectory)
            .collect();
        assert_eq!(ks, (0..10).chain([11]).collect::<Vec<_>>());
        // A radius so small that every cell coordinate is beyond the exact range.
        let config = SessionConfig {
            dedup_radius_m: 1e-300,
            ..config
        };
        let ks: Vec<u32> = select_markers(&c, &config)
            .iter()
            .map(|m| m.subtrajectory)
            .collect();
        assert_eq!(ks, (0..10).chain([11]).collect::<Vec<_>>());
    }

    fn arb_candidates() -> impl Strategy<Value = Vec<MarkerCandidate>> {
        prop::collection::vec((prop::array::uniform3(-3.0f64..3.0), 0.0f64..0.3), 0..200).prop_map(
            |v| {
                v.into_iter()
                    .enumerate()
                    .map(|(i, (p, e))| MarkerCandidate {
                        subtrajectory: i as u32,
                        position: DVec3::from_array(p),
                        normal: DVec3::Y,
                        error_m: e,
                    })
                    .collect()
            },
        )
    }

    /// The reference: the same cascade with a linear scan instead of the hash.
    fn brute_force(c: &[MarkerCandidate], config: &SessionConfig) -> Vec<u32> {
        let mut out: Vec<&MarkerCandidate> = Vec::new();
        for &t in &config.thresholds_m {
            for x in c {
                if out.len() < config.max_regions
                    && x.error_m >= t
                    && !out.iter().any(|m| m.subtrajectory == x.subtrajectory)
                    && out
                        .iter()
                        .all(|m| m.position.distance(x.position) > config.dedup_radius_m)
                {
                    out.push(x);
                }
            }
        }
        out.iter().map(|m| m.subtrajectory).collect()
    }

    proptest! {
        #[test]
        fn never_two_markers_within_the_radius(c in arb_candidates(), max in 0usize..12, radius in 0.0f64..2.0) {
            let config = SessionConfig { max_regions: max, dedup_radius_m: radius, ..SessionConfig::default() };
            let m = select_markers(&c, &config);
            prop_assert!(m.len() <= max);
            for (i, a) in m.iter().enumerate() {
                for b in &m[i + 1..] {
                    prop_assert!(a.position.distance(b.position) > radius);
                }
                prop_assert!(a.class == ErrorClass::High || a.class == ErrorClass::Medium);
                prop_assert!(a.error_m >= 0.01);
            }
            let ks: Vec<u32> = m.iter().map(|m| m.subtrajectory).collect();
            prop_assert_eq!(ks, brute_force(&c, &config));
        }

        #[test]
        fn arcore_rotation_is_the_converted_unity_rotation(n in prop::array::uniform3(-1.0f64..1.0)) {
            let n = DVec3::from_array(n);
            prop_assume!(n.length() > 0.1);
            let n = n.normalize();
            let unity = warning_sign_rotation(n, Convention::Unity);
            let arcore = warning_sign_rotation(Convention::Unity.convert_vector(n, Convention::Arcore), Convention::Arcore);
            let back = Convention::Arcore.convert_rotation(arcore, Convention::Unity);
            prop_assert!(back.dot(unity).abs() > 1.0 - 1e-12);
            prop_assert!((unity * DVec3::Y - n).length() < 1e-9);
        }
    }
}
