//! The render plan: plain data the Unity/Kotlin side instantiates.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::Pose;
use crate::logged_pose::LoggedPose;

/// A cylinder between two consecutive logged positions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// The sub-trajectory the segment lies in (colour it by that one's class).
    pub subtrajectory: u32,
    /// Midpoint of the two positions.
    pub centre: DVec3,
    /// Rotation taking local +Y along the segment (identity for a zero-length segment).
    pub rotation: DQuat,
    /// Distance between the two positions (metres); scale a unit cylinder's height by it.
    pub length: f64,
}

/// A sphere at a logged position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// Sub-trajectory: the one it starts (start pose), the midpoint's own, or the one an endpoint closes.
    pub subtrajectory: u32,
    /// Position (world).
    pub position: DVec3,
}

/// A camera frustum at a midpoint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Frustum {
    /// The midpoint's sub-trajectory.
    pub subtrajectory: u32,
    /// The camera pose at that midpoint.
    pub pose: Pose,
}

/// Everything needed to draw a trajectory, tagged with sub-trajectories so colours can be
/// applied once results arrive.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RenderPlan {
    /// One cylinder per pair of consecutive logged poses.
    pub segments: Vec<Segment>,
    /// One sphere per logged pose.
    pub joints: Vec<Joint>,
    /// A frustum at the first midpoint after every `frustum_spacing_m` of path.
    pub frustums: Vec<Frustum>,
    /// The start pose, once started.
    pub start: Option<Pose>,
    /// The stop pose, once stopped.
    pub stop: Option<Pose>,
}

/// Builds the plan from the logged poses (frame numbers from 0, every `n / 2` frames).
pub(crate) fn build(
    logged: &[LoggedPose],
    n: u32,
    spacing_m: f64,
    stop: Option<Pose>,
) -> RenderPlan {
    let half = n / 2;
    let joint_sub = |frame: u32| {
        if frame > 0 && frame.is_multiple_of(n) {
            frame / n - 1
        } else {
            frame / n
        }
    };
    let joints = logged
        .iter()
        .map(|l| Joint {
            subtrajectory: joint_sub(l.frame),
            position: l.pose.position,
        })
        .collect();
    let segments = logged
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].pose.position, w[1].pose.position);
            let d = b - a;
            let length = d.length();
            let rotation = if length > 0.0 {
                DQuat::from_rotation_arc(DVec3::Y, d / length)
            } else {
                DQuat::IDENTITY
            };
            Segment {
                subtrajectory: w[0].frame / n,
                centre: (a + b) * 0.5,
                rotation,
                length,
            }
        })
        .collect();
    let mut frustums = Vec::new();
    let mut next = spacing_m;
    for l in logged.iter().filter(|l| l.frame % n == half) {
        if l.path_m >= next {
            frustums.push(Frustum {
                subtrajectory: l.frame / n,
                pose: l.pose,
            });
            // One frustum however many increments this step crossed.
            next = ((l.path_m / spacing_m).floor() + 1.0) * spacing_m;
        }
    }
    RenderPlan {
        segments,
        joints,
        frustums,
        start: logged.first().map(|l| l.pose),
        stop,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn logged_line(count: u32, step_m: f64) -> Vec<LoggedPose> {
        (0..count)
            .map(|i| LoggedPose {
                t_ns: i64::from(i) * 166_666_667,
                frame: i * 5,
                pose: Pose::new(DVec3::new(f64::from(i) * step_m, 1.0, 0.0), DQuat::IDENTITY),
                path_m: f64::from(i) * step_m,
            })
            .collect()
    }

    #[test]
    fn segments_joints_and_tags() {
        let plan = build(&logged_line(5, 0.1), 10, 0.5, None);
        assert_eq!(plan.joints.len(), 5);
        assert_eq!(plan.segments.len(), 4);
        let seg_tags: Vec<u32> = plan.segments.iter().map(|s| s.subtrajectory).collect();
        assert_eq!(seg_tags, vec![0, 0, 1, 1]);
        let joint_tags: Vec<u32> = plan.joints.iter().map(|j| j.subtrajectory).collect();
        assert_eq!(joint_tags, vec![0, 0, 0, 1, 1]);
        let s = plan.segments[1];
        assert!((s.centre - DVec3::new(0.15, 1.0, 0.0)).length() < 1e-12);
        assert!((s.length - 0.1).abs() < 1e-12);
        // Local +Y along the segment (+X here).
        assert!((s.rotation * DVec3::Y - DVec3::X).length() < 1e-12);
        assert_eq!(plan.start, Some(logged_line(1, 0.1)[0].pose));
    }

    #[test]
    fn frustums_at_first_midpoint_after_each_spacing() {
        // Midpoints at path 0.1, 0.3, 0.5, 0.7, 0.9, 1.1 … (step 0.1 per logged pose).
        let plan = build(&logged_line(25, 0.1), 10, 0.5, None);
        let at: Vec<u32> = plan.frustums.iter().map(|f| f.subtrajectory).collect();
        // 0.5 → sub 2 (path 0.5), 1.0 → path 1.1 (sub 5), 1.5 → 1.5 (sub 7), 2.0 → 2.1 (sub 10).
        assert_eq!(at, vec![2, 5, 7, 10]);
        // A big jump crossing several increments yields one frustum, not several.
        // Midpoints at 0.7 and 2.1: the second step crosses 1.0, 1.5 and 2.0.
        let plan = build(&logged_line(4, 0.7), 10, 0.5, None);
        let at: Vec<u32> = plan.frustums.iter().map(|f| f.subtrajectory).collect();
        assert_eq!(at, vec![0, 1]);
    }
}
