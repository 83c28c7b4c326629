//! The phone's camera evidence (`crate::ingest::evidence`: properties, likely causes, thumbnails per
//! sub-trajectory) attached to the report's problem regions: each region shows the thumbnail
//! of its worst pictured sub-trajectory and its likely causes, each with a one-line reason
//! made of the measured value.

use std::collections::HashSet;

use crate::error::Error;
use crate::ingest::evidence::{EvidenceFiles, EvidenceRow};
use crate::report::regions::{CauseLine, Region, RegionEvidence, SubRow};
use crate::storage::BlobStore;

/// A session's stored evidence: the rows, and which sub-trajectories have a thumbnail.
pub(crate) struct CameraEvidence {
    rows: Vec<EvidenceRow>,
    thumbnails: HashSet<usize>,
}

impl CameraEvidence {
    /// The evidence of session `id`, none when the phone sent no `evidence.csv`.
    pub(crate) fn load(blobs: &dyn BlobStore, id: &str) -> Result<Option<Self>, Error> {
        let stored = EvidenceFiles { blobs, id };
        let Some(rows) = stored.evidence_rows()? else {
            return Ok(None);
        };
        let thumbnails = rows
            .iter()
            .filter(|r| r.image.is_some() && stored.has_thumbnail(r.index))
            .map(|r| r.index)
            .collect();
        Ok(Some(Self { rows, thumbnails }))
    }

    #[cfg(test)]
    pub(crate) fn from_parts(rows: Vec<EvidenceRow>, thumbnails: HashSet<usize>) -> Self {
        Self { rows, thumbnails }
    }

    fn row(&self, index: u32) -> Option<&EvidenceRow> {
        self.rows
            .get(index as usize)
            .filter(|r| r.index == index as usize)
    }
}

/// Fills `evidence` of every region: `image_url(k)` is the URL of sub-trajectory k's
/// thumbnail as the page's reader may fetch it (owner or share link).
pub(crate) fn attach(
    regions: &mut [Region],
    subs: &[SubRow],
    evidence: &CameraEvidence,
    image_url: &dyn Fn(u32) -> String,
) {
    for region in regions {
        // Members worst first (no estimate last).
        let mut members: Vec<&SubRow> = region
            .subtrajectories
            .iter()
            .filter_map(|k| subs.iter().find(|s| s.index == *k))
            .collect();
        members.sort_by(|a, b| {
            b.error
                .unwrap_or(f64::MIN)
                .total_cmp(&a.error.unwrap_or(f64::MIN))
        });
        let pictured = members
            .iter()
            .map(|s| s.index)
            .find(|k| evidence.thumbnails.contains(&(*k as usize)));
        let rows: Vec<&EvidenceRow> = members
            .iter()
            .filter_map(|s| evidence.row(s.index))
            .collect();
        let mut causes: Vec<CauseLine> = Vec::new();
        for row in &rows {
            for name in &row.causes {
                match causes.iter_mut().find(|c| c.name == *name) {
                    Some(c) => c.count += 1,
                    // The first row with the cause is the worst one: its numbers explain it.
                    None => causes.push(CauseLine {
                        name: name.clone(),
                        reason: reason(name, row),
                        count: 1,
                    }),
                }
            }
        }
        // Stable: equally frequent causes keep the worst sub-trajectory's order.
        causes.sort_by_key(|c| std::cmp::Reverse(c.count));
        region.evidence = Some(RegionEvidence {
            pictured,
            thumbnail_url: pictured.map(image_url),
            causes,
            covered: rows.len(),
        });
    }
}

/// One line on cause `name` of `row`: the measured value and what it means for tracking.
fn reason(name: &str, row: &EvidenceRow) -> String {
    let image = row.image.as_ref();
    match name {
        "low_texture" => format!(
            "{:.1} corners per 10 000 px: too few features to track (a blank wall or floor)",
            image.map_or(0.0, |p| p.corners_per_10k)
        ),
        "dark" => format!(
            "mean brightness {:.0} of 255: too dark for features",
            image.map_or(0.0, |p| p.mean_brightness)
        ),
        "overexposed" => format!(
            "{:.0} % of the pixels saturated: washed out (a window or a lamp)",
            image.map_or(0.0, |p| p.saturated_share * 100.0)
        ),
        "blur" => format!(
            "sharpness (Laplacian variance) {:.0}: motion blur or defocus",
            image.map_or(0.0, |p| p.laplacian_var)
        ),
        "fast_motion" => format!(
            "moving {:.2} m/s, turning {:.0}°/s: the camera moved fast",
            row.linear_speed_m_s, row.angular_speed_deg_s
        ),
        "far_surface" => format!(
            "the surface faced was {:.1} m away: far for depth and features",
            row.distance_m
        ),
        "no_depth" => format!(
            "depth valid on {:.0} % of the sample: glass or a mirror, likely",
            row.depth_valid_share.unwrap_or(0.0) * 100.0
        ),
        other => format!("{other} (as the phone reported it)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sitar_core::{ErrorClass, ImageProperties};

    fn row(index: usize, causes: &[&str], corners: f64) -> EvidenceRow {
        EvidenceRow {
            index,
            image: Some(ImageProperties {
                mean_brightness: 120.0,
                contrast_std: 30.0,
                laplacian_var: 200.0,
                corners_per_10k: corners,
                saturated_share: 0.0,
            }),
            thumbnail_size: Some((64, 48)),
            depth_valid_share: Some(0.2),
            linear_speed_m_s: 0.4,
            angular_speed_deg_s: 20.0,
            depth_valid: true,
            distance_m: 2.0,
            causes: causes.iter().map(|c| c.to_string()).collect(),
        }
    }

    fn sub(index: u32, error: Option<f64>) -> SubRow {
        SubRow {
            index,
            t0: 0.0,
            t1: 1.0,
            length_m: 0.3,
            error,
            class: ErrorClass::High,
            surface: None,
            interval: None,
        }
    }

    fn region(members: &[u32]) -> Region {
        Region {
            rank: 1,
            subtrajectories: members.to_vec(),
            stretches: 1,
            t0: 0.0,
            t1: 1.0,
            distance_m: 0.3,
            max_error: 0.2,
            mean_error: 0.2,
            class: ErrorClass::High,
            surface: None,
            markers: vec![],
            evidence: None,
            interval: None,
        }
    }

    #[test]
    fn the_worst_pictured_member_and_the_most_frequent_causes() {
        let rows = vec![
            row(0, &[], 40.0),
            row(1, &["no_depth"], 30.0),
            row(2, &["low_texture", "no_depth"], 1.5),
            row(3, &["low_texture"], 2.5),
        ];
        // Sub-trajectory 2 is the worst but has no thumbnail: 3 (next worst) is pictured.
        let evidence = CameraEvidence::from_parts(rows, [1, 3].into_iter().collect());
        let subs = vec![
            sub(0, Some(0.01)),
            sub(1, Some(0.12)),
            sub(2, Some(0.30)),
            sub(3, Some(0.20)),
        ];
        let mut regions = vec![region(&[1, 2, 3]), region(&[0])];
        attach(&mut regions, &subs, &evidence, &|k| format!("/img/{k}"));
        let e = regions[0].evidence.as_ref().unwrap();
        assert_eq!(e.pictured, Some(3));
        assert_eq!(e.thumbnail_url.as_deref(), Some("/img/3"));
        assert_eq!(e.covered, 3);
        let names: Vec<(&str, usize)> = e
            .causes
            .iter()
            .map(|c| (c.name.as_str(), c.count))
            .collect();
        assert_eq!(names, [("low_texture", 2), ("no_depth", 2)]);
        // The reason quotes the worst sub-trajectory with the cause (2: 1.5 corners).
        assert!(
            e.causes[0].reason.starts_with("1.5 corners per 10 000 px"),
            "{}",
            e.causes[0].reason
        );
        assert!(
            e.causes[1].reason.contains("20 %"),
            "{}",
            e.causes[1].reason
        );
        // A region whose only member has neither image nor cause.
        let e = regions[1].evidence.as_ref().unwrap();
        assert_eq!((e.pictured, e.causes.len(), e.covered), (None, 0, 1));
    }

    #[test]
    fn rows_beyond_the_table_are_not_evidence() {
        let evidence = CameraEvidence::from_parts(vec![row(0, &["dark"], 40.0)], HashSet::new());
        let mut regions = vec![region(&[5])];
        attach(&mut regions, &[sub(5, Some(0.3))], &evidence, &|k| {
            k.to_string()
        });
        let e = regions[0].evidence.as_ref().unwrap();
        assert_eq!((e.pictured, e.covered, e.causes.len()), (None, 0, 0));
    }
}
