//! Time association of two trajectories, as evo's `sync.associate_trajectories`.

use crate::{Error, Trajectory};

/// Converts seconds to whole nanoseconds (rounded).
pub fn seconds_to_ns(seconds: f64) -> i64 {
    (seconds * 1e9).round() as i64
}

/// Indices of the best-matching stamps, as evo's `matching_time_indices`: for every stamp of
/// `stamps_1` (in order) the nearest of `stamps_2 + offset_2_ns`, kept if within
/// `max_diff_ns`; on an exact tie the earlier stamp of `stamps_2` wins. Indices of
/// `stamps_2` may repeat. Unsorted `stamps_2` are searched linearly (evo's fallback, for
/// which it warns "Timestamps aren't sorted"); repeated stamps count as sorted.
pub fn matching_time_indices(
    stamps_1: &[i64],
    stamps_2: &[i64],
    max_diff_ns: i64,
    offset_2_ns: i64,
) -> (Vec<usize>, Vec<usize>) {
    let mut ids_1 = Vec::with_capacity(stamps_1.len().min(stamps_2.len()));
    let mut ids_2 = Vec::with_capacity(ids_1.capacity());
    let n2 = stamps_2.len();
    if n2 == 0 {
        return (ids_1, ids_2);
    }
    let shifted = |k: usize| stamps_2[k].saturating_add(offset_2_ns);
    if (1..n2).any(|k| shifted(k) < shifted(k - 1)) {
        for (index_1, &stamp_1) in stamps_1.iter().enumerate() {
            let (best, diff) = (0..n2)
                .map(|k| (k, shifted(k).abs_diff(stamp_1)))
                .fold((0, u64::MAX), |acc, x| if x.1 < acc.1 { x } else { acc });
            if diff <= max_diff_ns.unsigned_abs() {
                ids_1.push(index_1);
                ids_2.push(best);
            }
        }
        return (ids_1, ids_2);
    }
    let (first, last) = (shifted(0), shifted(n2 - 1));
    // `upper` is numpy's searchsorted(side="right"): the first k with stamps_2[k] > stamp_1.
    let mut upper = 0usize;
    let mut previous = i64::MIN;
    for (index_1, &stamp_1) in stamps_1.iter().enumerate() {
        if stamp_1 < first.saturating_sub(max_diff_ns) || stamp_1 > last.saturating_add(max_diff_ns)
        {
            continue;
        }
        if stamp_1 < previous {
            upper = stamps_2.partition_point(|&s| s.saturating_add(offset_2_ns) <= stamp_1);
        } else {
            while upper < n2 && shifted(upper) <= stamp_1 {
                upper += 1;
            }
        }
        previous = stamp_1;
        let k = upper.min(n2 - 1);
        let diff_ub = shifted(k).saturating_sub(stamp_1);
        let diff_lb = if k > 0 {
            stamp_1.saturating_sub(shifted(k - 1))
        } else {
            i64::MAX
        };
        let best = if diff_ub <= max_diff_ns && diff_ub < diff_lb {
            k
        } else if diff_lb <= max_diff_ns && diff_lb <= diff_ub {
            k - 1
        } else {
            continue;
        };
        ids_1.push(index_1);
        ids_2.push(best);
    }
    (ids_1, ids_2)
}

/// Matched index lists `(ids_1, ids_2)` of two trajectories as evo's `associate_trajectories`:
/// the trajectory with fewer poses (the second one on equal length) is walked and matched
/// into the other; `offset_s` shifts the second trajectory's stamps. Errors if nothing matches.
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
    let (max_diff, offset) = (seconds_to_ns(max_diff_s), seconds_to_ns(offset_s));
    let second_longer = traj_2.len() > traj_1.len();
    let (ids_1, ids_2) = if second_longer {
        matching_time_indices(&traj_1.stamps, &traj_2.stamps, max_diff, offset)
    } else {
        let (short, long) =
            matching_time_indices(&traj_2.stamps, &traj_1.stamps, max_diff, -offset);
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
