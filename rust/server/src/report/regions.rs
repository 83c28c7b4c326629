//! Problem regions: what the report lists instead of overlapping windows.
//!
//! Each sub-trajectory (10 frames, not overlapping) takes the error of its window. Runs of
//! consecutive medium/high sub-trajectories are merged into one stretch; stretches whose
//! faced surface points lie within `dedup_radius_m` (0.5 m, the markers' rule) of a region's
//! surface join that region. A region is thus one place in the room that tracking found
//! hard, however often the walk passed it.

use glam::DVec3;
use sitar_core::{ErrorClass, Marker, Session, SessionConfig, Thresholds};

/// One sub-trajectory as the report shows it.
#[derive(Debug, Clone)]
pub(crate) struct SubRow {
    pub index: u32,
    /// Start and end, seconds after the session's start.
    pub t0: f64,
    pub t1: f64,
    /// Path length through its frames (metres).
    pub length_m: f64,
    /// Error in the results' unit (metres or degrees), if a window matched.
    pub error: Option<f64>,
    pub class: ErrorClass,
    /// The surface point its midpoint's depth sample hit.
    pub surface: Option<DVec3>,
    /// The calibrated results' interval of its window (lower, upper; the results' unit),
    /// none in uncalibrated results.
    pub interval: Option<(f64, f64)>,
}

/// A problem region: one place, one or more stretches of medium/high sub-trajectories.
#[derive(Debug, Clone)]
pub(crate) struct Region {
    /// 1 = the worst.
    pub rank: usize,
    pub subtrajectories: Vec<u32>,
    /// Stretches of consecutive sub-trajectories merged into this region.
    pub stretches: usize,
    pub t0: f64,
    pub t1: f64,
    pub distance_m: f64,
    pub max_error: f64,
    pub mean_error: f64,
    pub class: ErrorClass,
    /// The mean faced surface point (none without depth).
    pub surface: Option<DVec3>,
    /// Markers (1-based, the phone's order) placed in this region.
    pub markers: Vec<usize>,
    /// The camera evidence of the place (`crate::report::region_evidence`), when the phone sent it.
    pub evidence: Option<RegionEvidence>,
    /// The interval of its worst sub-trajectory (calibrated results only).
    pub interval: Option<(f64, f64)>,
}

/// What the phone's camera evidence says of one region.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RegionEvidence {
    /// The sub-trajectory pictured: the worst one with a stored thumbnail.
    pub pictured: Option<u32>,
    /// URL of its thumbnail, served by this backend.
    pub thumbnail_url: Option<String>,
    /// The likely causes seen in the region, the most frequent first.
    pub causes: Vec<CauseLine>,
    /// Sub-trajectories of the region the evidence table covers.
    pub covered: usize,
}

/// One likely cause of a region, in the user's words.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CauseLine {
    /// sitar-core's machine name (`low_texture`, `no_depth`, …).
    pub name: String,
    /// One line: the measured value and what it means, from the worst sub-trajectory with
    /// this cause.
    pub reason: String,
    /// Sub-trajectories of the region with this cause.
    pub count: usize,
}

/// The sub-trajectories of `session` with errors classified by `thresholds`.
pub(crate) fn sub_rows(session: &Session, thresholds: Thresholds) -> Vec<SubRow> {
    let logged = session.logged();
    let n = session.config().subtrajectory_frames;
    let t_start = logged.first().map_or(0, |l| l.t_ns);
    let path_at = |frame: u32| {
        // Logged frames are sorted: the path at the last logged pose at or before `frame`.
        let i = logged.partition_point(|l| l.frame <= frame);
        if i == 0 { 0.0 } else { logged[i - 1].path_m }
    };
    let errors = session.subtrajectory_errors();
    session
        .subtrajectories()
        .iter()
        .zip(errors)
        .map(|(s, error)| {
            let end = s.end_ns.unwrap_or(s.mid_ns);
            SubRow {
                index: s.index,
                t0: (s.start_ns - t_start) as f64 * 1e-9,
                t1: (end - t_start) as f64 * 1e-9,
                length_m: path_at(s.index * n + n) - path_at(s.index * n),
                error,
                class: error.map_or(ErrorClass::Unknown, |e| thresholds.classify(e)),
                surface: s.depth.sample().map(|d| d.point),
                interval: None,
            }
        })
        .collect()
}

/// Merges the medium/high sub-trajectories into regions, worst first.
pub(crate) fn regions(subs: &[SubRow], markers: &[Marker], radius_m: f64) -> Vec<Region> {
    let bad = |s: &SubRow| matches!(s.class, ErrorClass::Medium | ErrorClass::High);
    // Stretches of consecutive bad sub-trajectories.
    let mut stretches: Vec<Vec<&SubRow>> = Vec::new();
    for s in subs.iter().filter(|s| bad(s)) {
        match stretches.last_mut() {
            Some(last) if last.last().is_some_and(|p| p.index + 1 == s.index) => last.push(s),
            _ => stretches.push(vec![s]),
        }
    }
    let mut regions: Vec<(Vec<&SubRow>, usize)> = Vec::new();
    for stretch in stretches {
        let surface = mean_surface(&stretch);
        let joined = surface.and_then(|p| {
            regions.iter().position(|(members, _)| {
                mean_surface(members).is_some_and(|q| q.distance(p) <= radius_m)
            })
        });
        match joined {
            Some(i) => {
                regions[i].0.extend(stretch);
                regions[i].1 += 1;
            }
            None => regions.push((stretch, 1)),
        }
    }
    let mut out: Vec<Region> = regions
        .into_iter()
        .map(|(members, stretches)| {
            let errors: Vec<f64> = members.iter().filter_map(|s| s.error).collect();
            let max_error = errors.iter().copied().fold(f64::MIN, f64::max);
            let worst_member = members
                .iter()
                .max_by(|a, b| a.error.unwrap_or(0.0).total_cmp(&b.error.unwrap_or(0.0)));
            let worst = worst_member.map_or(ErrorClass::Unknown, |s| s.class);
            let indices: Vec<u32> = members.iter().map(|s| s.index).collect();
            Region {
                rank: 0,
                stretches,
                t0: members.iter().map(|s| s.t0).fold(f64::MAX, f64::min),
                t1: members.iter().map(|s| s.t1).fold(f64::MIN, f64::max),
                distance_m: members.iter().map(|s| s.length_m).sum(),
                max_error,
                mean_error: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
                class: worst,
                surface: mean_surface(&members),
                markers: markers
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| indices.contains(&m.subtrajectory))
                    .map(|(i, _)| i + 1)
                    .collect(),
                subtrajectories: indices,
                evidence: None,
                interval: worst_member.and_then(|s| s.interval),
            }
        })
        .collect();
    out.sort_by(|a, b| b.max_error.total_cmp(&a.max_error));
    for (i, r) in out.iter_mut().enumerate() {
        r.rank = i + 1;
    }
    out
}

/// The marker tier (the phone's thresholds searched in order, 10, 5, 2, 1 cm by default)
/// an error of `error` reaches first, in the results' unit: the tier a marker was placed at.
pub(crate) fn marker_tier(phone: &Session, error: f64) -> Option<f64> {
    phone
        .config()
        .marker_thresholds()
        .iter()
        .copied()
        .find(|&t| error >= t)
}

/// Why a medium or high `region` has no marker, by the paper's marker rule (a marker needs
/// a depth sample; it is never within `dedup_radius_m` of another; at most `max_regions`
/// are placed): none when it has one.
pub(crate) fn why_no_marker(
    region: &Region,
    subs: &[SubRow],
    markers: &[Marker],
    config: &SessionConfig,
) -> Option<String> {
    if !region.markers.is_empty() {
        return None;
    }
    let sampled: Vec<DVec3> = region
        .subtrajectories
        .iter()
        .filter_map(|k| subs.iter().find(|s| s.index == *k))
        .filter(|s| s.error.is_some())
        .filter_map(|s| s.surface)
        .collect();
    if sampled.is_empty() {
        return Some(
            "no depth sample: the camera measured no surface here (glass, a mirror, or out \
             of depth range?), and a marker needs one"
                .into(),
        );
    }
    let radius = config.dedup_radius_m;
    let near = markers
        .iter()
        .enumerate()
        .find(|(_, m)| sampled.iter().all(|p| p.distance(m.position) <= radius));
    if let Some((i, _)) = near {
        return Some(format!(
            "within {radius} m of marker M{}, which stands for this place",
            i + 1
        ));
    }
    if markers.len() >= config.max_regions {
        return Some(format!(
            "over the maximum: the phone places at most {} markers, the worst tiers first",
            config.max_regions
        ));
    }
    Some("its faced surface points lie within the markers' radius of other markers".into())
}

fn mean_surface(members: &[&SubRow]) -> Option<DVec3> {
    let points: Vec<DVec3> = members.iter().filter_map(|s| s.surface).collect();
    (!points.is_empty()).then(|| points.iter().sum::<DVec3>() / points.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sub(index: u32, error: f64, surface: Option<DVec3>) -> SubRow {
        let t = Thresholds {
            medium: 0.05,
            high: 0.10,
        };
        SubRow {
            index,
            t0: f64::from(index),
            t1: f64::from(index) + 1.0,
            length_m: 0.5,
            error: Some(error),
            class: t.classify(error),
            surface,
            interval: None,
        }
    }

    #[test]
    fn consecutive_windows_merge_and_the_same_surface_joins() {
        let wall = Some(DVec3::new(0.0, 1.0, 2.0));
        let glass = Some(DVec3::new(3.0, 1.0, 0.0));
        let subs = vec![
            sub(0, 0.01, None),
            sub(1, 0.12, wall),
            sub(2, 0.07, wall.map(|p| p + DVec3::X * 0.2)),
            sub(3, 0.01, None),
            sub(4, 0.06, glass),
            sub(5, 0.02, None),
            // Back at the wall (0.3 m from the first stretch's mean): the same region.
            sub(6, 0.08, wall.map(|p| p + DVec3::X * 0.4)),
        ];
        let r = regions(&subs, &[], 0.5);
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].subtrajectories, vec![1, 2, 6]);
        assert_eq!(r[0].stretches, 2);
        assert_eq!(r[0].class, ErrorClass::High);
        assert!((r[0].max_error - 0.12).abs() < 1e-12);
        assert!((r[0].distance_m - 1.5).abs() < 1e-12);
        assert_eq!((r[0].t0, r[0].t1), (1.0, 7.0));
        assert_eq!(r[1].subtrajectories, vec![4]);
        assert_eq!(r[1].rank, 2);
    }

    #[test]
    fn a_region_without_a_marker_says_why() {
        let wall = DVec3::new(0.0, 1.0, 2.0);
        let config = SessionConfig::default();
        let marker = |p: DVec3, k: u32| Marker {
            position: p,
            rotation: glam::DQuat::IDENTITY,
            upright: glam::DQuat::IDENTITY,
            normal: DVec3::Z,
            class: ErrorClass::High,
            subtrajectory: k,
            error_m: 0.12,
        };
        // Glass: no surface point.
        let subs = vec![sub(0, 0.2, None), sub(1, 0.01, Some(wall))];
        let r = regions(&subs, &[], 0.5);
        let why = why_no_marker(&r[0], &subs, &[], &config).unwrap();
        assert!(why.starts_with("no depth sample"), "{why}");
        // Next to marker 1 (of another stretch, 0.3 m away).
        let subs = vec![
            sub(0, 0.2, Some(wall)),
            sub(1, 0.01, None),
            sub(2, 0.07, Some(wall + DVec3::X * 0.3)),
        ];
        let markers = [marker(wall, 0)];
        let r = regions(&subs, &markers, 0.0);
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].markers, vec![1]);
        assert_eq!(why_no_marker(&r[0], &subs, &markers, &config), None);
        let why = why_no_marker(&r[1], &subs, &markers, &config).unwrap();
        assert_eq!(
            why,
            "within 0.5 m of marker M1, which stands for this place"
        );
        // Three markers elsewhere: the maximum.
        let far = |x: f64| marker(DVec3::new(x, 0.0, 9.0), 9);
        let markers = [far(0.0), far(2.0), far(4.0)];
        let why = why_no_marker(&r[1], &subs, &markers, &config).unwrap();
        assert!(
            why.starts_with("over the maximum: the phone places at most 3"),
            "{why}"
        );
    }

    #[test]
    fn without_depth_only_consecutive_stretches_merge() {
        let subs = vec![sub(0, 0.2, None), sub(1, 0.2, None), sub(3, 0.2, None)];
        let r = regions(&subs, &[], 0.5);
        assert_eq!(r.len(), 2);
    }
}
