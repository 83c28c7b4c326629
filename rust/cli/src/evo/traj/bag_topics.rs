//! The topics of a ROS bag that `sitar traj` reads, as evo_traj picks them.

use anyhow::{Result, bail};
use sitar_estimator::Trajectory;

use crate::evo::traj::args::Options;
use crate::evo::traj::bundle::Bundle;
use crate::io::console::Console;

/// The topics of a bag that `traj` reads.
pub(super) struct BagSelection<'a> {
    /// evo's format: `bag` or `bag2`.
    pub(super) kind: &'a str,
    pub(super) bag: &'a str,
    pub(super) topics: &'a [String],
    pub(super) all_topics: bool,
}

/// evo_traj's topics of a ROS bag: those given, and with `--all_topics` every topic of a
/// pose type evo reads (sorted; `--ref` left out of them), each named by its topic; `--ref`
/// is a topic too.
pub(super) fn read_bag_topics(
    bundle: &mut Bundle,
    selection: &BagSelection<'_>,
    options: &Options,
    console: &Console,
) -> Result<()> {
    let BagSelection {
        kind,
        bag,
        topics,
        all_topics,
    } = *selection;
    if topics.is_empty() && !all_topics {
        bail!("No topics used - specify topics or set --all_topics.");
    }
    let reference = options
        .reference
        .as_ref()
        .map(|r| r.to_string_lossy().into_owned());
    let wanted = if all_topics {
        crate::io::bag::Wanted::All
    } else {
        crate::io::bag::Wanted::named(topics.iter().chain(&reference))
    };
    let content = crate::io::bag::open(kind, bag, &wanted, console)?;
    let mut chosen = topics.to_vec();
    if all_topics {
        chosen.extend(crate::io::bag::supported_topics(&content));
        chosen.retain(|t| Some(t) != reference.as_ref());
        if chosen.is_empty() {
            bail!(
                "{bag}: found no topics of supported types (geometry_msgs/msg/PoseStamped, PoseWithCovarianceStamped, TransformStamped, PointStamped, nav_msgs/msg/Odometry)"
            );
        }
    }
    let mut read = |topic: &String| -> Result<Trajectory> {
        let read = crate::io::bag::trajectory(&content, topic, bag, console)?;
        if read.quaternions_off_unit > 0 {
            bundle.off_unit.insert(topic.clone());
        }
        bundle.frames.insert(topic.clone(), read.frame_id);
        Ok(read.trajectory)
    };
    let mut trajectories: Vec<(String, Trajectory)> = Vec::new();
    for topic in chosen {
        if trajectories.iter().all(|(n, _)| *n != topic) {
            let trajectory = read(&topic)?;
            trajectories.push((topic, trajectory));
        }
    }
    let reference = match reference {
        Some(topic) => Some((topic.clone(), read(&topic)?)),
        None => None,
    };
    bundle.trajectories = trajectories;
    bundle.reference = reference;
    Ok(())
}
