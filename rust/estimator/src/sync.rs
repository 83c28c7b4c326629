//! Time association of two trajectories, as evo's `sync.associate_trajectories`.

use crate::{Error, Trajectory};

/// Converts seconds to whole nanoseconds: the float's exact value rounded to the nearest
/// nanosecond (halves away from zero), so a float of evo's seconds above 2²⁵ s (where floats
/// are further apart than 2 ns) comes back from [`crate::TimeUnit::seconds`] unchanged. Saturates
/// beyond ±9.2·10⁹ s; NaN is 0.
pub fn seconds_to_ns(seconds: f64) -> i64 {
    if seconds.is_nan() || seconds.abs() >= 9.2e9 {
        return (seconds * 1e9) as i64;
    }
    let bits = seconds.abs().to_bits();
    let (exponent, fraction) = ((bits >> 52) as i32, bits & ((1 << 52) - 1));
    let (mantissa, shift) = if exponent == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1 << 52), exponent - 1075)
    };
    let scaled = i128::from(mantissa) * 1_000_000_000;
    let ns = if shift >= 0 {
        scaled << shift
    } else if shift > -127 {
        (scaled + (1 << (-shift - 1))) >> -shift
    } else {
        0
    };
    let ns = ns as i64;
    if seconds < 0.0 { -ns } else { ns }
}

/// A stamp type evo's matching runs on: integer nanoseconds (saturating) or float64 seconds
/// (as evo's numpy arrays, rounding included).
trait StampValue: Copy + PartialOrd {
    /// Larger than any difference (evo's `float("inf")` for a missing lower neighbour).
    const INFINITE: Self;
    const ZERO: Self;
    fn plus(self, other: Self) -> Self;
    fn minus(self, other: Self) -> Self;
}

impl StampValue for i64 {
    const INFINITE: Self = i64::MAX;
    const ZERO: Self = 0;
    fn plus(self, other: Self) -> Self {
        self.saturating_add(other)
    }
    fn minus(self, other: Self) -> Self {
        self.saturating_sub(other)
    }
}

impl StampValue for f64 {
    const INFINITE: Self = f64::INFINITY;
    const ZERO: Self = 0.0;
    fn plus(self, other: Self) -> Self {
        self + other
    }
    fn minus(self, other: Self) -> Self {
        self - other
    }
}

/// evo's `matching_time_indices` on any stamp type (see [`matching_time_indices`]).
fn match_stamps<T: StampValue>(
    stamps_1: &[T],
    stamps_2: &[T],
    max_diff: T,
    offset_2: T,
) -> (Vec<usize>, Vec<usize>) {
    let mut ids_1 = Vec::with_capacity(stamps_1.len().min(stamps_2.len()));
    let mut ids_2 = Vec::with_capacity(ids_1.capacity());
    let n2 = stamps_2.len();
    if n2 == 0 {
        return (ids_1, ids_2);
    }
    // evo shifts a copy of stamps_2 (`stamps_2 += offset_2`), rounding as it goes.
    let shifted: Vec<T> = stamps_2.iter().map(|&s| s.plus(offset_2)).collect();
    let distance = |a: T, b: T| if a >= b { a.minus(b) } else { b.minus(a) };
    // evo: `np.all(np.diff(stamps_2) >= 0)`, else a linear search with numpy's argmin (the
    // first of equal minima).
    if !shifted.windows(2).all(|w| w[1].minus(w[0]) >= T::ZERO) {
        for (index_1, &stamp_1) in stamps_1.iter().enumerate() {
            let mut best = (0, distance(shifted[0], stamp_1));
            for (k, &s) in shifted.iter().enumerate().skip(1) {
                let d = distance(s, stamp_1);
                if d < best.1 {
                    best = (k, d);
                }
            }
            if best.1 <= max_diff {
                ids_1.push(index_1);
                ids_2.push(best.0);
            }
        }
        return (ids_1, ids_2);
    }
    let (first, last) = (shifted[0], shifted[n2 - 1]);
    // `upper` is numpy's searchsorted(side="right"): the first k with stamps_2[k] > stamp_1.
    let mut upper = 0usize;
    let mut previous: Option<T> = None;
    for (index_1, &stamp_1) in stamps_1.iter().enumerate() {
        if stamp_1 < first.minus(max_diff) || stamp_1 > last.plus(max_diff) {
            continue;
        }
        if previous.is_some_and(|p| stamp_1 < p) {
            upper = shifted.partition_point(|&s| s <= stamp_1);
        } else {
            while upper < n2 && shifted[upper] <= stamp_1 {
                upper += 1;
            }
        }
        previous = Some(stamp_1);
        let k = upper.min(n2 - 1);
        let diff_ub = shifted[k].minus(stamp_1);
        let diff_lb = if k > 0 {
            stamp_1.minus(shifted[k - 1])
        } else {
            T::INFINITE
        };
        let best = if diff_ub <= max_diff && diff_ub < diff_lb {
            k
        } else if diff_lb <= max_diff && diff_lb <= diff_ub {
            k - 1
        } else {
            continue;
        };
        ids_1.push(index_1);
        ids_2.push(best);
    }
    (ids_1, ids_2)
}

/// Indices of the best-matching stamps, as evo's `matching_time_indices`, on integer
/// nanoseconds: for every stamp of `stamps_1` (in order) the nearest of
/// `stamps_2 + offset_2_ns`, kept if within `max_diff_ns`. Sorted `stamps_2` are searched
/// as evo does (binary search; the upper neighbour only when strictly closer, so an exact
/// tie goes to the lower one). Indices of `stamps_2` may repeat. Unsorted `stamps_2` are
/// searched linearly (evo's fallback, for which it warns "Timestamps aren't sorted"; the
/// first of equal distances wins); repeated stamps count as sorted.
pub fn matching_time_indices(
    stamps_1: &[i64],
    stamps_2: &[i64],
    max_diff_ns: i64,
    offset_2_ns: i64,
) -> (Vec<usize>, Vec<usize>) {
    match_stamps(stamps_1, stamps_2, max_diff_ns, offset_2_ns)
}

/// [`matching_time_indices`] on float64 seconds, rounding exactly as evo's numpy arithmetic
/// does: the offset is added to each stamp of `stamps_2`, the differences are float
/// differences, so a decimal tie (1311868226.310950 halfway between .3093 and .3126) is
/// decided by how the floats round, as in evo.
pub fn matching_time_indices_seconds(
    stamps_1: &[f64],
    stamps_2: &[f64],
    max_diff_s: f64,
    offset_2_s: f64,
) -> (Vec<usize>, Vec<usize>) {
    match_stamps(stamps_1, stamps_2, max_diff_s, offset_2_s)
}

/// The matching of `short` into `long` as evo makes it: on evo's float64 seconds (see
/// [`Trajectory::seconds`]) when either was read in seconds, on integer nanoseconds (same
/// rule, exact arithmetic) when both are nanoseconds. `offset_s` shifts `long`.
pub fn match_trajectories(
    short: &Trajectory,
    long: &Trajectory,
    max_diff_s: f64,
    offset_s: f64,
) -> (Vec<usize>, Vec<usize>) {
    let in_seconds = short.time_unit.is_seconds() || long.time_unit.is_seconds();
    if in_seconds {
        matching_time_indices_seconds(&short.seconds(), &long.seconds(), max_diff_s, offset_s)
    } else {
        matching_time_indices(
            &short.stamps,
            &long.stamps,
            seconds_to_ns(max_diff_s),
            seconds_to_ns(offset_s),
        )
    }
}

/// Matched index lists `(ids_1, ids_2)` of two trajectories as evo's `associate_trajectories`:
/// the trajectory with fewer poses (the second one on equal length) is walked and matched
/// into the other ([`match_trajectories`]: float64 seconds as evo's when either was read in
/// seconds); `offset_s` shifts the second trajectory's stamps. Errors if nothing matches.
/// Stamps may repeat or be unsorted, as evo allows (see [`matching_time_indices`]).
pub fn associate(
    traj_1: &Trajectory,
    traj_2: &Trajectory,
    max_diff_s: f64,
    offset_s: f64,
) -> Result<(Vec<usize>, Vec<usize>), Error> {
    traj_1.validate_poses()?;
    traj_2.validate_poses()?;
    associate_named(
        traj_1,
        traj_2,
        max_diff_s,
        offset_s,
        ("first trajectory", "second trajectory"),
    )
}

/// [`associate`] with names for the error message; the caller has validated both.
pub(crate) fn associate_named(
    traj_1: &Trajectory,
    traj_2: &Trajectory,
    max_diff_s: f64,
    offset_s: f64,
    names: (&str, &str),
) -> Result<(Vec<usize>, Vec<usize>), Error> {
    let valid = max_diff_s.is_finite() && max_diff_s >= 0.0 && offset_s.is_finite();
    if !valid {
        return Err(Error::InvalidArgument(format!(
            "max_diff must be a finite non-negative number of seconds and offset finite (got {max_diff_s}, {offset_s})"
        )));
    }
    let second_longer = traj_2.len() > traj_1.len();
    let (ids_1, ids_2) = if second_longer {
        match_trajectories(traj_1, traj_2, max_diff_s, offset_s)
    } else {
        let (short, long) = match_trajectories(traj_2, traj_1, max_diff_s, -offset_s);
        (long, short)
    };
    if ids_1.is_empty() {
        return Err(Error::NoMatches {
            first: names.0.to_owned(),
            second: names.1.to_owned(),
            max_diff_s,
            offset_s,
        });
    }
    Ok((ids_1, ids_2))
}

/// Synchronised copies of both trajectories (same length, poses at matching stamps), as evo's
/// `associate_trajectories` with `SyncMethod.nearest_time`.
pub fn associate_trajectories(
    traj_1: &Trajectory,
    traj_2: &Trajectory,
    max_diff_s: f64,
    offset_s: f64,
) -> Result<(Trajectory, Trajectory), Error> {
    let (ids_1, ids_2) = associate(traj_1, traj_2, max_diff_s, offset_s)?;
    Ok((traj_1.reduce_to_ids(&ids_1), traj_2.reduce_to_ids(&ids_2)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeUnit;

    /// evo's linear-search definition, for comparison.
    fn brute(s1: &[i64], s2: &[i64], max: i64, off: i64) -> (Vec<usize>, Vec<usize>) {
        let mut out = (vec![], vec![]);
        for (i, &a) in s1.iter().enumerate() {
            let (best, diff) = s2
                .iter()
                .enumerate()
                .map(|(k, &b)| (k, (b + off - a).abs()))
                .fold((0, i64::MAX), |acc, x| if x.1 < acc.1 { x } else { acc });
            if diff <= max {
                out.0.push(i);
                out.1.push(best);
            }
        }
        out
    }

    #[test]
    fn seconds_to_ns_is_exact() {
        assert_eq!(seconds_to_ns(1.5), 1_500_000_000);
        assert_eq!(seconds_to_ns(-0.25), -250_000_000);
        assert_eq!(seconds_to_ns(0.0), 0);
        assert_eq!(seconds_to_ns(f64::NAN), 0);
        assert_eq!(seconds_to_ns(1e300), i64::MAX);
        assert_eq!(seconds_to_ns(1e-300), 0);
        // The float nearest 1311868226.31095 is 1311868226.31095004081…: exactly, not via a
        // rounded product.
        let f: f64 = "1311868226.310950".parse().unwrap();
        assert_eq!(seconds_to_ns(f), 1_311_868_226_310_950_041);
        assert_eq!(TimeUnit::Seconds.seconds(seconds_to_ns(f)), f);
    }

    proptest::proptest! {
        /// Floats of seconds above 2²⁵ s survive the trip through nanoseconds.
        #[test]
        fn large_seconds_round_trip(f in 33_554_432.0f64..9.0e9) {
            proptest::prop_assert_eq!(TimeUnit::Seconds.seconds(seconds_to_ns(f)), f);
        }
    }

    #[test]
    fn nearest_with_ties_to_the_earlier() {
        let (a, b) = matching_time_indices(&[0, 15, 30, 100], &[10, 20, 31], 10, 0);
        assert_eq!(a, vec![0, 1, 2]);
        assert_eq!(b, vec![0, 0, 2]);
        let (a, b) = matching_time_indices(&[5, 26], &[0, 10, 20], 5, 0);
        assert_eq!((a, b), (vec![0], vec![0]));
        let (a, b) = matching_time_indices(&[25], &[0, 10, 20], 5, 0);
        assert_eq!((a, b), (vec![0], vec![2]));
    }

    proptest::proptest! {
        #[test]
        fn matches_linear_search(mut s1 in proptest::collection::vec(-100i64..100, 0..30),
                                 mut s2 in proptest::collection::vec(-100i64..100, 1..30),
                                 max in 0i64..20, off in -20i64..20) {
            s1.sort_unstable(); s1.dedup(); s2.sort_unstable(); s2.dedup();
            proptest::prop_assert_eq!(matching_time_indices(&s1, &s2, max, off), brute(&s1, &s2, max, off));
        }

        /// Repeated and unsorted stamps on either side (evo keeps both): still the linear
        /// search's answer, except that a repeated stamp of a sorted `stamps_2` matches its
        /// last copy (numpy's searchsorted right side), not the first.
        #[test]
        fn repeated_and_unsorted_stamps(s1 in proptest::collection::vec(-50i64..50, 0..30),
                                        mut s2 in proptest::collection::vec(-50i64..50, 1..30),
                                        sort in proptest::bool::ANY, max in 0i64..20) {
            if sort { s2.sort_unstable(); }
            let (a, b) = matching_time_indices(&s1, &s2, max, 0);
            let (ba, bb) = brute(&s1, &s2, max, 0);
            proptest::prop_assert_eq!(&a, &ba);
            for (k, (&got, &want)) in b.iter().zip(&bb).enumerate() {
                proptest::prop_assert_eq!((s2[got] - s1[a[k]]).abs(), (s2[want] - s1[a[k]]).abs());
                if !s2.windows(2).all(|w| w[0] <= w[1]) { proptest::prop_assert_eq!(got, want); }
            }
        }
    }

    /// The TUM fr2/desk tie: ORB's stamp 1311868226.310950 lies exactly halfway between the
    /// ground truth's .3093 and .3126 as decimals; as evo's floats the upper one is closer by
    /// 2.4e-7 s and wins (evo_ape matches index 1). Integer nanoseconds see the exact tie and
    /// keep the lower one.
    #[test]
    fn decimal_tie_decided_by_float_rounding_as_evo() {
        let gt: [f64; 2] = [
            "1311868226.3093".parse().unwrap(),
            "1311868226.3126".parse().unwrap(),
        ];
        let est: f64 = "1311868226.310950".parse().unwrap();
        assert_eq!(
            matching_time_indices_seconds(&[est], &gt, 0.01, 0.0),
            (vec![0], vec![1])
        );
        let ns = [1_311_868_226_309_300_000, 1_311_868_226_312_600_000];
        assert_eq!(
            matching_time_indices(&[1_311_868_226_310_950_000], &ns, 10_000_000, 0),
            (vec![0], vec![0])
        );
        let make = |stamps: Vec<i64>, time_unit| Trajectory {
            positions: vec![glam::DVec3::ZERO; stamps.len()],
            orientations: vec![glam::DQuat::IDENTITY; stamps.len()],
            stamps,
            time_unit,
        };
        let seconds = crate::TimeUnit::Seconds;
        let (short, long) = (
            make(vec![1_311_868_226_310_950_000], seconds),
            make(ns.to_vec(), seconds),
        );
        assert_eq!(
            match_trajectories(&short, &long, 0.01, 0.0),
            (vec![0], vec![1])
        );
        let nanos = crate::TimeUnit::Nanoseconds;
        let (short, long) = (make(short.stamps, nanos), make(long.stamps, nanos));
        assert_eq!(
            match_trajectories(&short, &long, 0.01, 0.0),
            (vec![0], vec![0])
        );
    }

    proptest::proptest! {
        /// The float rule on stamps that floats hold exactly (multiples of 1/8 s) is the
        /// integer rule.
        #[test]
        fn float_rule_is_the_integer_rule_on_exact_stamps(
            s1 in proptest::collection::vec(-400i64..400, 0..30),
            mut s2 in proptest::collection::vec(-400i64..400, 1..30),
            sort in proptest::bool::ANY, max in 0i64..40, off in -40i64..40) {
            if sort { s2.sort_unstable(); }
            let f = |v: &[i64]| v.iter().map(|&x| x as f64 / 8.0).collect::<Vec<_>>();
            proptest::prop_assert_eq!(
                matching_time_indices_seconds(&f(&s1), &f(&s2), max as f64 / 8.0, off as f64 / 8.0),
                matching_time_indices(&s1, &s2, max, off)
            );
        }
    }

    #[test]
    fn shorter_trajectory_is_walked() {
        let make = |stamps: Vec<i64>| Trajectory {
            positions: vec![glam::DVec3::ZERO; stamps.len()],
            orientations: vec![glam::DQuat::IDENTITY; stamps.len()],
            stamps,
            time_unit: crate::TimeUnit::Nanoseconds,
        };
        let long = make(vec![0, 4_000_000, 8_000_000, 12_000_000]);
        let short = make(vec![3_000_000, 9_000_000]);
        let (i1, i2) = associate(&long, &short, 0.01, 0.0).unwrap();
        assert_eq!((i1, i2), (vec![1, 2], vec![0, 1]));
        let (i1, i2) = associate(&short, &long, 0.01, 0.0).unwrap();
        assert_eq!((i1, i2), (vec![0, 1], vec![1, 2]));
        assert!(matches!(
            associate(&short, &make(vec![1_000_000_000]), 0.01, 0.0),
            Err(Error::NoMatches { .. })
        ));
    }
}
