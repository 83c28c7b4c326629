//! Trajectories in ROS bags, as evo reads them: the pose messages evo reads
//! (`geometry_msgs/msg/PoseStamped`, `PoseWithCovarianceStamped`, `TransformStamped`,
//! `PointStamped` with a unit quaternion, `nav_msgs/msg/Odometry`) decoded from CDR
//! (`cdr-encoding`, ROS 2) or the ROS 1 serialization ([`crate::ros1`]), each pose stamped
//! with its header's stamp as evo's float `sec + nanosec * 1e-9` ([`TimeUnit::RosStamp`]);
//! MCAP storage (uncompressed, zstd or lz4 chunks) read with Foxglove's `mcap` reader. The
//! container of the sqlite3 storage is read by the caller (it hands over each message's
//! bytes).

use std::collections::BTreeMap;

use glam::DQuat;
use serde::Deserialize;

use crate::pose_messages::{
    Encoding, Odometry, PoseMessage, StampedPoint, StampedPose, StampedPoseValue, StampedTransform,
    TopicMessages, quaternion, vector,
};
use crate::{Error, TimeUnit, Trajectory};

/// Splits a CDR message into its body and byte order (from the encapsulation header).
fn cdr_body(data: &[u8]) -> Result<(&[u8], bool), Error> {
    let bad = |what: String| Error::InvalidArgument(format!("CDR message: {what}"));
    let (header, body) = data
        .split_first_chunk::<4>()
        .ok_or_else(|| bad(format!("{} bytes, shorter than its header", data.len())))?;
    let little = match header[1] {
        0 | 2 => false,
        1 | 3 => true,
        other => return Err(bad(format!("unknown encapsulation kind {other}"))),
    };
    Ok((body, little))
}

/// Deserializes a CDR message (header included) as `T`.
pub(crate) fn decode_cdr<T: for<'de> Deserialize<'de>>(data: &[u8]) -> Result<T, Error> {
    let (body, little) = cdr_body(data)?;
    let result = if little {
        cdr_encoding::from_bytes::<T, byteorder::LittleEndian>(body)
    } else {
        cdr_encoding::from_bytes::<T, byteorder::BigEndian>(body)
    };
    result
        .map(|(value, _)| value)
        .map_err(|e| Error::InvalidArgument(format!("CDR message: {e}")))
}

/// Decodes one CDR-encoded message (4 bytes of encapsulation header, then the body) of
/// type `kind`.
pub fn decode_pose(kind: PoseMessage, data: &[u8]) -> Result<StampedPoseValue, Error> {
    let (header, position, orientation) = match kind {
        PoseMessage::PoseStamped | PoseMessage::PoseWithCovarianceStamped => {
            let m: StampedPose = decode_cdr(data)?;
            let p = m.pose;
            (m.header, vector(p.position), quaternion(p.orientation))
        }
        PoseMessage::Odometry => {
            let m: Odometry = decode_cdr(data)?;
            let p = m.pose;
            (m.header, vector(p.position), quaternion(p.orientation))
        }
        PoseMessage::TransformStamped => {
            let m: StampedTransform = decode_cdr(data)?;
            (m.header, vector(m.translation), quaternion(m.rotation))
        }
        PoseMessage::PointStamped => {
            let m: StampedPoint = decode_cdr(data)?;
            (m.header, vector(m.point), DQuat::IDENTITY)
        }
    };
    Ok(StampedPoseValue {
        stamp_ns: header.stamp.ns(),
        position,
        orientation,
        frame_id: header.frame_id,
    })
}

/// Decodes one message of `kind` serialized as `encoding`.
pub fn decode_pose_as(
    kind: PoseMessage,
    encoding: Encoding,
    data: &[u8],
) -> Result<StampedPoseValue, Error> {
    match encoding {
        Encoding::Cdr => decode_pose(kind, data),
        Encoding::Ros1 => crate::ros1::decode_ros1_pose(kind, data),
    }
}

/// Every topic of an MCAP file (topics advertised without messages included, with none),
/// messages in log-time order.
pub fn read_mcap(bytes: &[u8]) -> Result<BTreeMap<String, TopicMessages>, Error> {
    read_mcap_topics(bytes, &|_| true)
}

/// [`read_mcap`] keeping the messages of the topics `wanted` says yes to only (the others
/// are listed with their types and no messages): a bag's images are never copied.
pub fn read_mcap_topics(
    bytes: &[u8],
    wanted: &dyn Fn(&str) -> bool,
) -> Result<BTreeMap<String, TopicMessages>, Error> {
    read_mcap_from(bytes, wanted)
}

/// The largest MCAP record (a chunk, compressed or not) the streaming reader buffers.
const MAX_MCAP_RECORD: usize = 1 << 30;

/// [`read_mcap_topics`] from a reader, streamed (Foxglove's sans-I/O reader): the file is
/// never held whole, only one record (at most 1 GiB) and the wanted topics' messages.
pub fn read_mcap_from(
    mut input: impl std::io::Read,
    wanted: &dyn Fn(&str) -> bool,
) -> Result<BTreeMap<String, TopicMessages>, Error> {
    use mcap::records::Record;
    use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let bad = |e: mcap::McapError| Error::InvalidArgument(format!("MCAP: {e}"));
    let options = LinearReaderOptions::default().with_record_length_limit(MAX_MCAP_RECORD);
    let mut reader = LinearReader::new_with_options(options);
    let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
    let mut channels: BTreeMap<u16, (String, bool)> = BTreeMap::new();
    let mut topics: BTreeMap<String, TopicMessages> = BTreeMap::new();
    let mut stamped: BTreeMap<u16, Vec<(u64, Vec<u8>)>> = BTreeMap::new();
    while let Some(event) = reader.next_event() {
        match event.map_err(bad)? {
            LinearReadEvent::ReadRequest(need) => {
                let read = input
                    .read(reader.insert(need))
                    .map_err(|e| Error::InvalidArgument(format!("MCAP: {e}")))?;
                reader.notify_read(read);
            }
            LinearReadEvent::Record { opcode, data } => match mcap::parse_record(opcode, data)
                .map_err(bad)?
            {
                Record::Schema { header, .. } => {
                    schemas.insert(header.id, header.name);
                }
                Record::Channel(channel) => {
                    let type_name = schemas.get(&channel.schema_id).cloned().unwrap_or_default();
                    let entry = topics.entry(channel.topic.clone()).or_default();
                    if entry.type_name.is_empty() {
                        entry.type_name = type_name;
                    }
                    let keep = wanted(&channel.topic);
                    channels.insert(channel.id, (channel.topic, keep));
                }
                Record::Message { header, data } => {
                    let Some((_, keep)) = channels.get(&header.channel_id) else {
                        return Err(Error::InvalidArgument(format!(
                            "MCAP: a message on channel {}, which no channel record defines",
                            header.channel_id
                        )));
                    };
                    if *keep {
                        let messages = stamped.entry(header.channel_id).or_default();
                        messages.push((header.log_time, data.into_owned()));
                    }
                }
                _ => {}
            },
        }
    }
    // Log-time order (stable), as rosbags (evo's reader) yields a bag's messages.
    for (channel, mut messages) in stamped {
        messages.sort_by_key(|m| m.0);
        let topic = channels
            .get(&channel)
            .map(|c| c.0.clone())
            .unwrap_or_default();
        let entry = topics.entry(topic).or_default();
        entry.messages.extend(messages.into_iter().map(|m| m.1));
    }
    Ok(topics)
}

/// A topic's trajectory with what evo shows of it.
#[derive(Debug, Clone, PartialEq)]
pub struct BagTrajectory {
    /// The poses (quaternions normalised).
    pub trajectory: Trajectory,
    /// The first message's `header.frame_id` (evo's `meta.frame_id`).
    pub frame_id: String,
    /// Quaternions whose norm is not 1 by numpy's `allclose` (evo's check).
    pub quaternions_off_unit: usize,
}

/// The trajectory of `topic` as evo reads it: one pose per message, stamped with its header
/// stamp (seconds, as evo's floats), in the bag's order. Errors name the topic and its type.
pub fn topic_trajectory(topic: &str, messages: &TopicMessages) -> Result<BagTrajectory, Error> {
    let kind = PoseMessage::from_type_name(&messages.type_name).ok_or_else(|| {
        Error::InvalidArgument(format!(
            "topic {topic}: unsupported message type {} (evo reads geometry_msgs/msg/PoseStamped, PoseWithCovarianceStamped, TransformStamped, PointStamped and nav_msgs/msg/Odometry)",
            if messages.type_name.is_empty() {
                "(none given)"
            } else {
                &messages.type_name
            }
        ))
    })?;
    if messages.messages.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "no messages for topic '{topic}' in bag"
        )));
    }
    let mut out = BagTrajectory {
        trajectory: Trajectory {
            time_unit: TimeUnit::RosStamp,
            ..Trajectory::default()
        },
        frame_id: String::new(),
        quaternions_off_unit: 0,
    };
    for (k, data) in messages.messages.iter().enumerate() {
        let pose = decode_pose_as(kind, messages.encoding, data).map_err(|e| {
            Error::InvalidArgument(format!(
                "topic {topic} ({}), message {}: {e}",
                messages.type_name,
                k + 1
            ))
        })?;
        let norm = pose.orientation.length();
        if !(pose.position.is_finite() && norm.is_finite() && norm > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "topic {topic} ({}), message {}: pose not finite or zero quaternion",
                messages.type_name,
                k + 1
            )));
        }
        if k == 0 {
            out.frame_id = pose.frame_id;
        }
        out.quaternions_off_unit += usize::from((norm - 1.0).abs() > 1e-8 + 1e-5);
        let t = &mut out.trajectory;
        t.stamps.push(pose.stamp_ns);
        t.positions.push(pose.position);
        t.orientations.push(pose.orientation / norm);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A little-endian CDR PoseStamped, laid out by hand as ROS 2 writes it.
    fn pose_stamped(sec: i32, nanosec: u32, frame: &str, values: [f64; 7]) -> Vec<u8> {
        let mut out = vec![0, 1, 0, 0];
        let body_start = out.len();
        out.extend(sec.to_le_bytes());
        out.extend(nanosec.to_le_bytes());
        out.extend((frame.len() as u32 + 1).to_le_bytes());
        out.extend(frame.as_bytes());
        out.push(0);
        while (out.len() - body_start) % 8 != 0 {
            out.push(0);
        }
        for v in values {
            out.extend(v.to_le_bytes());
        }
        out
    }

    #[test]
    fn decodes_pose_stamped_and_names_bad_messages() {
        let data = pose_stamped(
            1_311_868_226,
            310_950_000,
            "map",
            [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 2.0],
        );
        let pose = decode_pose(PoseMessage::PoseStamped, &data).unwrap();
        assert_eq!(pose.stamp_ns, 1_311_868_226_310_950_000);
        assert_eq!(pose.position, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(pose.orientation, DQuat::from_xyzw(0.0, 0.0, 0.0, 2.0));
        assert_eq!(pose.frame_id, "map");
        let one = TopicMessages {
            type_name: "geometry_msgs/msg/PoseStamped".into(),
            messages: vec![data.clone()],
            ..TopicMessages::default()
        };
        let read = topic_trajectory("/gt", &one).unwrap();
        assert_eq!(
            (read.frame_id.as_str(), read.quaternions_off_unit),
            ("map", 1)
        );
        assert_eq!(read.trajectory.orientations, [DQuat::IDENTITY]);
        // Odometry shares the layout up to its child frame: a short message is an error.
        assert!(decode_pose(PoseMessage::Odometry, &data).is_err());
        assert!(decode_pose(PoseMessage::PoseStamped, &data[..20]).is_err());
        assert!(decode_pose(PoseMessage::PoseStamped, &[0, 1]).is_err());
        let messages = TopicMessages {
            type_name: "geometry_msgs/msg/PoseStamped".into(),
            messages: vec![data.clone(), data[..12].to_vec()],
            ..TopicMessages::default()
        };
        let error = topic_trajectory("/gt", &messages).unwrap_err().to_string();
        assert!(
            error.contains("/gt") && error.contains("message 2"),
            "{error}"
        );
        let twist = TopicMessages {
            type_name: "geometry_msgs/msg/Twist".into(),
            messages: vec![data],
            ..TopicMessages::default()
        };
        let error = topic_trajectory("/cmd_vel", &twist)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("/cmd_vel") && error.contains("geometry_msgs/msg/Twist"),
            "{error}"
        );
    }

    proptest::proptest! {
        /// Any bytes, and any one-byte change or cut of a valid message: an error or a pose,
        /// never a panic (the fuzz target `rosbag` runs the same on a larger scale).
        #[test]
        fn bad_bytes_are_errors(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..200),
                                at in 0usize..200, value in proptest::num::u8::ANY, cut in 0usize..200) {
            let kinds = [PoseMessage::PoseStamped, PoseMessage::PoseWithCovarianceStamped,
                         PoseMessage::TransformStamped, PoseMessage::PointStamped, PoseMessage::Odometry];
            let mut valid = pose_stamped(7, 8, "frame", [0.5; 7]);
            let n = valid.len();
            valid[at % n] = value;
            valid.truncate(cut.max(1).min(n));
            for kind in kinds {
                let _ = decode_pose(kind, &bytes);
                let _ = decode_pose(kind, &valid);
            }
            let _ = read_mcap(&bytes);
        }
    }

    #[test]
    fn type_names_in_both_spellings() {
        assert_eq!(
            PoseMessage::from_type_name("nav_msgs/msg/Odometry"),
            Some(PoseMessage::Odometry)
        );
        assert_eq!(
            PoseMessage::from_type_name("geometry_msgs/PointStamped"),
            Some(PoseMessage::PointStamped)
        );
        assert_eq!(PoseMessage::from_type_name("tf2_msgs/msg/TFMessage"), None);
        assert!(read_mcap(b"not an mcap file").is_err());
    }
}
