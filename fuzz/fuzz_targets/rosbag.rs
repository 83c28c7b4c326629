//! ROS 2 bag readers: sitar-estimator's MCAP reader (`read_mcap`) on the raw bytes, and its
//! CDR pose decoder (`decode_pose`) for every message type evo reads, on the raw bytes and on
//! every message an MCAP that parses holds (and the tf message decoder on those). Errors are fine; a panic is not. What decodes
//! keeps its stamp as sec·10⁹ + nanosec and a finite or non-finite pose as written.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_estimator::{
    Encoding, PoseMessage, TopicMessages, decode_pose, decode_tf_message, read_mcap,
    topic_trajectory,
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
        if let Ok(pose) = decode_pose(kind, data) {
            // sec is an i32 and nanosec a u32: the stamp cannot overflow.
            assert!(pose.stamp_ns.unsigned_abs() < 1 << 62);
        }
    }
    if let Ok(topics) = read_mcap(data) {
        for (topic, messages) in &topics {
            if let Ok(read) = topic_trajectory(topic, messages) {
                assert_eq!(read.trajectory.len(), messages.messages.len());
            }
            for message in &messages.messages {
                let _ = decode_tf_message(Encoding::Cdr, message);
                let one = TopicMessages {
                    type_name: "nav_msgs/msg/Odometry".into(),
                    messages: vec![message.clone()],
                    ..TopicMessages::default()
                };
                let _ = topic_trajectory(topic, &one);
            }
        }
    }
});
