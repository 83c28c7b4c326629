//! ROS 1 bags: sitar-estimator's `read_ros1_bag` (its header check, then the `rosbag` crate
//! under `catch_unwind`) on the raw bytes written to a file, the ROS 1 pose decoder for every
//! message type evo reads and the tf message decoder on the raw bytes, and the tf lookup on
//! every bag that parses. Errors are fine; a panic or an unbounded allocation is not.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_estimator::{
    Encoding, PoseMessage, TfId, decode_ros1_pose, decode_tf_message, read_ros1_bag,
    tf_trajectory, topic_trajectory,
};

const KINDS: [PoseMessage; 5] = [
    PoseMessage::PoseStamped,
    PoseMessage::PoseWithCovarianceStamped,
    PoseMessage::TransformStamped,
    PoseMessage::PointStamped,
    PoseMessage::Odometry,
];

fuzz_target!(|data: &[u8]| {
    for kind in KINDS {
        if let Ok(pose) = decode_ros1_pose(kind, data) {
            assert!(pose.stamp_ns.unsigned_abs() < 1 << 62);
        }
    }
    if let Ok(transforms) = decode_tf_message(Encoding::Ros1, data) {
        assert!(transforms.len() <= data.len());
    }
    // The reader maps a file: the bytes go to one per process.
    let path = std::env::temp_dir().join(format!("sitar-fuzz-{}.bag", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(topics) = read_ros1_bag(&path) {
        for (topic, messages) in &topics {
            if let Ok(read) = topic_trajectory(topic, messages) {
                assert_eq!(read.trajectory.len(), messages.messages.len());
            }
        }
        if let Ok(Some(id)) = TfId::parse("/tf:map.base") {
            let _ = tf_trajectory(&topics, &id, "/tf:map.base");
        }
    }
});
