//! Trajectories written into ROS bags as evo's `--save_as_bag`/`--save_as_bag2` writes them
//! (through rosbags): one `geometry_msgs/PoseStamped` topic per trajectory, each pose
//! stamped with evo's `sec = floor(t)`, `nanosec = int((t - sec) * 1e9)` of its float64
//! seconds, logged at `int(t * 1e9)` ns; ROS 1 headers count `seq` from 0 per topic. ROS 1:
//! an uncompressed bag (format 2.0) with one chunk and its index; ROS 2: an MCAP file
//! (Foxglove's writer, the `ros2msg` schema and `cdr` channels rosbags writes) and the
//! rosbag2 `metadata.yaml` (version 9) that goes beside it.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::{Error, Trajectory};

/// A trajectory and the topic and frame it is written with.
#[derive(Debug, Clone, Copy)]
pub struct PoseTopic<'a> {
    /// The topic (`/ground_truth`).
    pub topic: &'a str,
    /// The header's `frame_id`.
    pub frame_id: &'a str,
    /// The poses.
    pub trajectory: &'a Trajectory,
}

/// The ROS 1 definition of `geometry_msgs/PoseStamped` and its MD5, as rosbags generates them.
const ROS1_DEFINITION: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n================================================================================\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
const ROS1_MD5: &str = "d3812c3cbc69362b77dc0b19b345f8f5";
/// The ROS 2 definition, as rosbags puts it in the MCAP schema.
const ROS2_DEFINITION: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Pose\ngeometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n================================================================================\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
/// rosbag2's type hash of `geometry_msgs/msg/PoseStamped`.
const ROS2_TYPE_HASH: &str =
    "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8";
const TYPE_NAME: &str = "geometry_msgs/msg/PoseStamped";

/// One pose as evo writes it: the header stamp, the bag's log time (ns) and the values.
struct Stamped {
    sec: i32,
    nanosec: u32,
    log_ns: u64,
    values: [f64; 7],
}

/// The poses of `trajectory` with evo's stamps (see the module docs).
fn stamped(trajectory: &Trajectory) -> Vec<Stamped> {
    (0..trajectory.len())
        .map(|k| {
            let t = trajectory.time_unit.seconds(trajectory.stamps[k]);
            let sec = t.floor();
            let (p, q) = (trajectory.positions[k], trajectory.orientations[k]);
            Stamped {
                sec: sec as i32,
                nanosec: ((t - sec) * 1e9) as u32,
                log_ns: (t * 1e9) as u64,
                values: [p.x, p.y, p.z, q.x, q.y, q.z, q.w],
            }
        })
        .collect()
}

/// A ROS 1 record: its header fields and data.
fn ros1_record(out: &mut Vec<u8>, fields: &[(&str, &[u8])], data: &[u8]) {
    let header_len: usize = fields.iter().map(|(k, v)| 4 + k.len() + 1 + v.len()).sum();
    out.extend((header_len as u32).to_le_bytes());
    for (key, value) in fields {
        out.extend(((key.len() + 1 + value.len()) as u32).to_le_bytes());
        out.extend(key.as_bytes());
        out.push(b'=');
        out.extend(*value);
    }
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(data);
}

fn ros1_time(ns: u64) -> [u8; 8] {
    let mut out = [0; 8];
    out[..4].copy_from_slice(&((ns / 1_000_000_000) as u32).to_le_bytes());
    out[4..].copy_from_slice(&((ns % 1_000_000_000) as u32).to_le_bytes());
    out
}

/// A ROS 1 bag (format 2.0, one uncompressed chunk) holding `topics`.
pub fn ros1_bag(topics: &[PoseTopic<'_>]) -> Vec<u8> {
    let mut chunk = Vec::new();
    let mut connections = Vec::new();
    // Per connection: (time, offset in the chunk) of each message.
    let mut index: Vec<Vec<(u64, u32)>> = Vec::new();
    let (mut start, mut end) = (u64::MAX, 0);
    for (id, topic) in topics.iter().enumerate() {
        let id_bytes = (id as u32).to_le_bytes();
        let mut connection = Vec::new();
        ros1_record(
            &mut connection,
            &[
                ("op", &[7]),
                ("conn", &id_bytes),
                ("topic", topic.topic.as_bytes()),
            ],
            &[],
        );
        // The connection header is the data: a field list without the length prefix.
        connection.truncate(connection.len() - 4);
        let mut fields = Vec::new();
        for (key, value) in [
            ("topic", topic.topic),
            ("type", "geometry_msgs/PoseStamped"),
            ("md5sum", ROS1_MD5),
            ("message_definition", ROS1_DEFINITION),
        ] {
            fields.extend(((key.len() + 1 + value.len()) as u32).to_le_bytes());
            fields.extend(key.as_bytes());
            fields.push(b'=');
            fields.extend(value.as_bytes());
        }
        connection.extend((fields.len() as u32).to_le_bytes());
        connection.extend(&fields);
        chunk.extend(&connection);
        connections.push(connection);
        let mut entries = Vec::new();
        for (seq, pose) in stamped(topic.trajectory).into_iter().enumerate() {
            let mut message = Vec::with_capacity(80);
            message.extend((seq as u32).to_le_bytes());
            message.extend(pose.sec.to_le_bytes());
            message.extend(pose.nanosec.to_le_bytes());
            message.extend((topic.frame_id.len() as u32).to_le_bytes());
            message.extend(topic.frame_id.as_bytes());
            for v in pose.values {
                message.extend(v.to_le_bytes());
            }
            entries.push((pose.log_ns, chunk.len() as u32));
            (start, end) = (start.min(pose.log_ns), end.max(pose.log_ns));
            ros1_record(
                &mut chunk,
                &[
                    ("op", &[2]),
                    ("conn", &id_bytes),
                    ("time", &ros1_time(pose.log_ns)),
                ],
                &message,
            );
        }
        index.push(entries);
    }
    let start = if start == u64::MAX { 0 } else { start };
    let mut body = Vec::new();
    let chunk_pos_in_body = body.len();
    ros1_record(
        &mut body,
        &[
            ("op", &[5]),
            ("compression", b"none"),
            ("size", &(chunk.len() as u32).to_le_bytes()),
        ],
        &chunk,
    );
    for (id, entries) in index.iter().enumerate() {
        let mut data = Vec::with_capacity(entries.len() * 12);
        for (time, offset) in entries {
            data.extend(ros1_time(*time));
            data.extend(offset.to_le_bytes());
        }
        ros1_record(
            &mut body,
            &[
                ("op", &[4]),
                ("ver", &1u32.to_le_bytes()),
                ("conn", &(id as u32).to_le_bytes()),
                ("count", &(entries.len() as u32).to_le_bytes()),
            ],
            &data,
        );
    }
    // The bag header record is padded to 4096 bytes, as ROS writes it.
    const MAGIC: &[u8] = b"#ROSBAG V2.0\n";
    const HEADER_RECORD: usize = 4096;
    let first_record = MAGIC.len() + HEADER_RECORD;
    let index_pos = (first_record + body.len()) as u64;
    for connection in &connections {
        body.extend(connection);
    }
    let mut counts = Vec::new();
    for (id, entries) in index.iter().enumerate() {
        counts.extend((id as u32).to_le_bytes());
        counts.extend((entries.len() as u32).to_le_bytes());
    }
    ros1_record(
        &mut body,
        &[
            ("op", &[6]),
            ("ver", &1u32.to_le_bytes()),
            (
                "chunk_pos",
                &((first_record + chunk_pos_in_body) as u64).to_le_bytes(),
            ),
            ("start_time", &ros1_time(start)),
            ("end_time", &ros1_time(end)),
            ("count", &(topics.len() as u32).to_le_bytes()),
        ],
        &counts,
    );
    let mut out = MAGIC.to_vec();
    let mut header = Vec::new();
    let fields: [(&str, &[u8]); 4] = [
        ("op", &[3]),
        ("index_pos", &index_pos.to_le_bytes()),
        ("conn_count", &(topics.len() as u32).to_le_bytes()),
        ("chunk_count", &1u32.to_le_bytes()),
    ];
    ros1_record(&mut header, &fields, &[]);
    let padding = HEADER_RECORD - header.len();
    header.truncate(header.len() - 4);
    header.extend((padding as u32).to_le_bytes());
    header.resize(HEADER_RECORD, b' ');
    out.extend(header);
    out.extend(body);
    out
}

#[derive(Serialize)]
struct Time {
    sec: i32,
    nanosec: u32,
}

#[derive(Serialize)]
struct PoseStamped<'a> {
    stamp: Time,
    frame_id: &'a str,
    values: [f64; 7],
}

/// A CDR `PoseStamped` with its little-endian encapsulation header.
fn cdr_pose(pose: &Stamped, frame_id: &str) -> Result<Vec<u8>, Error> {
    let message = PoseStamped {
        stamp: Time {
            sec: pose.sec,
            nanosec: pose.nanosec,
        },
        frame_id,
        values: pose.values,
    };
    let body = cdr_encoding::to_vec::<_, byteorder::LittleEndian>(&message)
        .map_err(|e| Error::InvalidArgument(format!("CDR: {e}")))?;
    Ok([&[0, 1, 0, 0][..], &body].concat())
}

/// An MCAP file (ROS 2 storage, uncompressed chunks as rosbags writes) holding `topics`.
pub fn mcap_bag(topics: &[PoseTopic<'_>]) -> Result<Vec<u8>, Error> {
    let bad = |e: mcap::McapError| Error::InvalidArgument(format!("MCAP: {e}"));
    let options = mcap::WriteOptions::new()
        .profile("ros2")
        .library("sitar")
        .compression(None);
    let mut writer = options
        .create(std::io::Cursor::new(Vec::new()))
        .map_err(bad)?;
    let schema = writer
        .add_schema(TYPE_NAME, "ros2msg", ROS2_DEFINITION.as_bytes())
        .map_err(bad)?;
    for topic in topics {
        let metadata = BTreeMap::from([("offered_qos_profiles".to_owned(), "[]".to_owned())]);
        let channel = writer
            .add_channel(schema, topic.topic, "cdr", &metadata)
            .map_err(bad)?;
        for (sequence, pose) in stamped(topic.trajectory).iter().enumerate() {
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: sequence as u32,
                log_time: pose.log_ns,
                publish_time: pose.log_ns,
            };
            writer
                .write_to_known_channel(&header, &cdr_pose(pose, topic.frame_id)?)
                .map_err(bad)?;
        }
    }
    writer.finish().map_err(bad)?;
    Ok(writer.into_inner().into_inner())
}

/// The rosbag2 `metadata.yaml` (version 9, MCAP storage) of a bag whose one file is
/// `file_name`, holding `topics` as [`mcap_bag`] writes them.
pub fn rosbag2_metadata(file_name: &str, topics: &[PoseTopic<'_>]) -> String {
    let times: Vec<u64> = topics
        .iter()
        .flat_map(|t| stamped(t.trajectory).into_iter().map(|s| s.log_ns))
        .collect();
    let start = times.iter().copied().min().unwrap_or(0);
    let duration = times.iter().copied().max().unwrap_or(0) - start;
    let count = times.len();
    let quoted = |s: &str| format!("'{}'", s.replace('\'', "''"));
    let mut topic_list = String::new();
    for topic in topics {
        topic_list.push_str(&format!(
            "  - message_count: {}\n    topic_metadata:\n      name: {}\n      offered_qos_profiles: []\n      serialization_format: cdr\n      type: {TYPE_NAME}\n      type_description_hash: {ROS2_TYPE_HASH}\n",
            topic.trajectory.len(),
            quoted(topic.topic)
        ));
    }
    let file = quoted(file_name);
    format!(
        "rosbag2_bagfile_information:\n  compression_format: ''\n  compression_mode: ''\n  custom_data: null\n  duration:\n    nanoseconds: {duration}\n  files:\n  - duration:\n      nanoseconds: {duration}\n    message_count: {count}\n    path: {file}\n    starting_time:\n      nanoseconds_since_epoch: {start}\n  message_count: {count}\n  relative_file_paths:\n  - {file}\n  ros_distro: sitar\n  starting_time:\n    nanoseconds_since_epoch: {start}\n  storage_identifier: mcap\n  topics_with_message_count:\n{topic_list}  version: 9\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{TimeUnit, read_mcap, topic_trajectory};
    use glam::{DQuat, DVec3};

    fn trajectory() -> Trajectory {
        Trajectory {
            stamps: vec![1_305_031_098_665_900_000, 1_305_031_098_675_900_000],
            positions: vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(-1.0, 0.5, 0.25)],
            orientations: vec![DQuat::IDENTITY, DQuat::from_rotation_y(0.5)],
            time_unit: TimeUnit::Seconds,
        }
    }

    /// What is written reads back (MCAP through the reader, ROS 1 through `rosbag`): the
    /// poses, the frame, and evo's stamps within 1 µs of the originals.
    #[test]
    fn written_bags_read_back() {
        let t = trajectory();
        let topics = [PoseTopic {
            topic: "/est",
            frame_id: "map",
            trajectory: &t,
        }];
        let mcap = mcap_bag(&topics).unwrap();
        let read = read_mcap(&mcap).unwrap();
        let dir = std::env::temp_dir().join(format!("sitar-bagw-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("t.bag"), ros1_bag(&topics)).unwrap();
        let ros1 = crate::read_ros1_bag(&dir.join("t.bag")).unwrap();
        // Unwanted topics are listed with their type, without their messages.
        let skipped = crate::read_ros1_bag_topics(&dir.join("t.bag"), &|_| false).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        for skipped in [
            skipped,
            crate::read_mcap_topics(&mcap, &|t| t != "/est").unwrap(),
        ] {
            assert_eq!(skipped["/est"].type_name, TYPE_NAME);
            assert!(skipped["/est"].messages.is_empty());
        }
        for topics in [read, ros1] {
            assert_eq!(topics["/est"].type_name, TYPE_NAME);
            let back = topic_trajectory("/est", &topics["/est"]).unwrap();
            assert_eq!(back.frame_id, "map");
            assert_eq!(back.trajectory.positions, t.positions);
            for (a, b) in back.trajectory.orientations.iter().zip(&t.orientations) {
                assert!(a.angle_between(*b) < 1e-12);
            }
            for (a, b) in back.trajectory.stamps.iter().zip(&t.stamps) {
                assert!((a - b).abs() < 1_000, "{a} {b}");
            }
        }
        let yaml = rosbag2_metadata("x.mcap", &topics);
        assert!(yaml.contains("message_count: 2") && yaml.contains("name: '/est'"));
    }
}
