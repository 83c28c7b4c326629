//! ROS 1 bags (format 2.0), as evo reads them with rosbags: the `rosbag` crate reads the
//! container (uncompressed, bz2 and lz4 chunks); messages are decoded here from the ROS 1
//! serialization (little-endian, unaligned, `Header` with a `seq`). The bag's own header is
//! checked first and the reader runs under `catch_unwind`, so a malformed file is an error
//! naming it, never a crash.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use glam::{DQuat, DVec3};

use crate::Error;
use crate::pose_messages::{
    Encoding, Header, Pose, PoseMessage, Quaternion, StampedPoseValue, StampedTransform, Time,
    TopicMessages, Vector,
};

const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

/// A cursor over ROS 1 serialized bytes; every read names what ran short.
pub(crate) struct Ros1Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Ros1Reader<'a> {
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Self { data, at: 0 }
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], Error> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(Error::InvalidArgument(format!(
                "ROS 1 message: {} bytes end inside {what} (at byte {})",
                self.data.len(),
                self.at
            )));
        };
        let bytes = &self.data[self.at..end];
        self.at = end;
        Ok(bytes)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], Error> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(N, what)?);
        Ok(out)
    }

    pub(crate) fn u32(&mut self, what: &str) -> Result<u32, Error> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    fn f64(&mut self, what: &str) -> Result<f64, Error> {
        Ok(f64::from_le_bytes(self.array(what)?))
    }

    fn string(&mut self, what: &str) -> Result<String, Error> {
        let n = self.u32(what)? as usize;
        let bytes = self.take(n, what)?;
        String::from_utf8(bytes.to_vec())
            .map_err(|_| Error::InvalidArgument(format!("ROS 1 message: {what} is not UTF-8")))
    }

    fn vector(&mut self, what: &str) -> Result<Vector, Error> {
        Ok(Vector {
            x: self.f64(what)?,
            y: self.f64(what)?,
            z: self.f64(what)?,
        })
    }

    fn quaternion(&mut self) -> Result<Quaternion, Error> {
        let what = "the orientation";
        Ok(Quaternion {
            x: self.f64(what)?,
            y: self.f64(what)?,
            z: self.f64(what)?,
            w: self.f64(what)?,
        })
    }

    pub(crate) fn header(&mut self) -> Result<Header, Error> {
        let _seq = self.u32("the header")?;
        let sec = i32::from_le_bytes(self.array("the header")?);
        let nanosec = self.u32("the header")?;
        Ok(Header {
            stamp: Time { sec, nanosec },
            frame_id: self.string("the header's frame_id")?,
        })
    }

    fn pose(&mut self) -> Result<Pose, Error> {
        Ok(Pose {
            position: self.vector("the position")?,
            orientation: self.quaternion()?,
        })
    }

    /// `geometry_msgs/TransformStamped`.
    pub(crate) fn transform_stamped(&mut self) -> Result<StampedTransform, Error> {
        Ok(StampedTransform {
            header: self.header()?,
            child_frame_id: self.string("child_frame_id")?,
            translation: self.vector("the translation")?,
            rotation: self.quaternion()?,
        })
    }
}

/// Decodes one ROS 1 serialized message of type `kind`.
pub fn decode_ros1_pose(kind: PoseMessage, data: &[u8]) -> Result<StampedPoseValue, Error> {
    let mut r = Ros1Reader::new(data);
    let (header, position, orientation) = match kind {
        PoseMessage::PoseStamped | PoseMessage::PoseWithCovarianceStamped => {
            let header = r.header()?;
            let pose = r.pose()?;
            (header, pose.position, pose.orientation)
        }
        PoseMessage::Odometry => {
            let header = r.header()?;
            let _child = r.string("child_frame_id")?;
            let pose = r.pose()?;
            (header, pose.position, pose.orientation)
        }
        PoseMessage::TransformStamped => {
            let t = r.transform_stamped()?;
            (t.header, t.translation, t.rotation)
        }
        PoseMessage::PointStamped => {
            let header = r.header()?;
            let point = r.vector("the point")?;
            let one = Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            };
            (header, point, one)
        }
    };
    Ok(StampedPoseValue {
        stamp_ns: header.stamp.ns(),
        position: DVec3::new(position.x, position.y, position.z),
        orientation: DQuat::from_xyzw(orientation.x, orientation.y, orientation.z, orientation.w),
        frame_id: header.frame_id,
    })
}

/// The ROS 2 spelling of a ROS 1 type name (`geometry_msgs/PoseStamped` →
/// `geometry_msgs/msg/PoseStamped`), as rosbags (evo's reader) names ROS 1 types.
fn ros2_type_name(name: &str) -> String {
    match name.split_once('/') {
        Some((package, kind)) if !kind.contains('/') => format!("{package}/msg/{kind}"),
        _ => name.to_owned(),
    }
}

/// Checks the bag's magic and header record (`index_pos` within the file) before the reader
/// sees it: the `rosbag` crate slices the file with these numbers unchecked.
fn check_header(path: &Path) -> Result<(), Error> {
    let io = |source| Error::Io {
        path: path.to_owned(),
        source,
    };
    let bad = |what: &str| Error::InvalidArgument(format!("{}: {what}", path.display()));
    let metadata = std::fs::metadata(path).map_err(io)?;
    if metadata.is_dir() {
        return Err(bad("a directory, not a ROS 1 bag (a ROS 2 bag? use bag2)"));
    }
    let file_len = metadata.len();
    let mut start = vec![0; 4096.min(file_len as usize)];
    std::fs::File::open(path)
        .map_err(io)?
        .read_exact(&mut start)
        .map_err(io)?;
    if !start.starts_with(MAGIC) {
        return Err(bad(
            "not a ROS 1 bag (no '#ROSBAG V2.0' line; a ROS 2 bag? use bag2)",
        ));
    }
    let mut r = Ros1Reader::new(&start[MAGIC.len()..]);
    let header_len = r
        .u32("the bag header")
        .map_err(|_| bad("bag header cut short"))?;
    let fields = r
        .take(header_len as usize, "the bag header")
        .map_err(|_| bad("bag header cut short"))?;
    let data_len = r
        .u32("the bag header")
        .map_err(|_| bad("bag header cut short"))?;
    let chunks_start = (MAGIC.len() + 8) as u64 + u64::from(header_len) + u64::from(data_len);
    let mut index_pos = None;
    let mut f = Ros1Reader::new(fields);
    while f.at < fields.len() {
        let n = f.u32("a field").map_err(|_| bad("bad bag header field"))? as usize;
        let field = f
            .take(n, "a field")
            .map_err(|_| bad("bad bag header field"))?;
        if let Some(value) = field.strip_prefix(b"index_pos=") {
            let bytes: [u8; 8] = value
                .try_into()
                .map_err(|_| bad("bag header: index_pos is not 8 bytes"))?;
            index_pos = Some(u64::from_le_bytes(bytes));
        }
    }
    match index_pos {
        None => Err(bad("bag header without index_pos")),
        Some(0) => Err(bad(
            "the bag is not indexed (its recording was cut short: run `rosbag reindex` on it)",
        )),
        Some(p) if p < chunks_start || p > file_len => Err(bad(&format!(
            "bag header: index_pos {p} outside the file's {file_len} bytes"
        ))),
        Some(_) => Ok(()),
    }
}

/// Every topic of the ROS 1 bag at `path` (connections without messages included, with
/// none), types named as rosbags names them (`geometry_msgs/msg/PoseStamped`), messages in
/// the bag's time order.
pub fn read_ros1_bag(path: &Path) -> Result<BTreeMap<String, TopicMessages>, Error> {
    read_ros1_bag_topics(path, &|_| true)
}

/// [`read_ros1_bag`] keeping the messages of the topics `wanted` says yes to only.
pub fn read_ros1_bag_topics(
    path: &Path,
    wanted: &dyn Fn(&str) -> bool,
) -> Result<BTreeMap<String, TopicMessages>, Error> {
    check_header(path)?;
    let read = || -> Result<BTreeMap<String, TopicMessages>, String> {
        let bag = rosbag::RosBag::new(path).map_err(|e| e.to_string())?;
        let mut connections: BTreeMap<u32, (String, String)> = BTreeMap::new();
        let mut stamped: Vec<(u64, u32, Vec<u8>)> = Vec::new();
        for record in bag.chunk_records() {
            let rosbag::ChunkRecord::Chunk(chunk) = record.map_err(|e| e.to_string())? else {
                continue;
            };
            for message in chunk.messages() {
                match message.map_err(|e| e.to_string())? {
                    rosbag::MessageRecord::Connection(c) => {
                        connections.insert(c.id, (c.topic.to_owned(), ros2_type_name(c.tp)));
                    }
                    rosbag::MessageRecord::MessageData(m) => {
                        // Connections come before their messages in a chunk.
                        let skip = connections.get(&m.conn_id).is_some_and(|c| !wanted(&c.0));
                        if !skip {
                            stamped.push((m.time, m.conn_id, m.data.to_vec()));
                        }
                    }
                }
            }
        }
        for record in bag.index_records() {
            if let rosbag::IndexRecord::Connection(c) = record.map_err(|e| e.to_string())? {
                connections.insert(c.id, (c.topic.to_owned(), ros2_type_name(c.tp)));
            }
        }
        let mut topics: BTreeMap<String, TopicMessages> = BTreeMap::new();
        for (topic, type_name) in connections.values() {
            let entry = topics.entry(topic.clone()).or_default();
            entry.type_name = type_name.clone();
            entry.encoding = Encoding::Ros1;
        }
        // Time order (stable), as rosbags yields a bag's messages.
        stamped.sort_by_key(|m| m.0);
        for (_, id, data) in stamped {
            let Some((topic, _)) = connections.get(&id) else {
                return Err(format!(
                    "a message of connection {id}, which the bag does not define"
                ));
            };
            if let Some(entry) = topics.get_mut(topic) {
                entry.messages.push(data);
            }
        }
        Ok(topics)
    };
    let bad = |e: String| Error::InvalidArgument(format!("{}: ROS 1 bag: {e}", path.display()));
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)) {
        Ok(result) => result.map_err(bad),
        Err(_) => Err(bad("malformed records (the reader gave up)".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ROS 1 PoseStamped, laid out by hand.
    fn pose_stamped(sec: u32, nsec: u32, frame: &str, values: [f64; 7]) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend(7u32.to_le_bytes());
        out.extend(sec.to_le_bytes());
        out.extend(nsec.to_le_bytes());
        out.extend((frame.len() as u32).to_le_bytes());
        out.extend(frame.as_bytes());
        for v in values {
            out.extend(v.to_le_bytes());
        }
        out
    }

    #[test]
    fn decodes_ros1_messages_and_names_short_ones() {
        let data = pose_stamped(12, 5, "map", [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0]);
        let pose = decode_ros1_pose(PoseMessage::PoseStamped, &data).unwrap();
        assert_eq!(pose.stamp_ns, 12_000_000_005);
        assert_eq!(pose.position, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(pose.frame_id, "map");
        let error = decode_ros1_pose(PoseMessage::PoseStamped, &data[..30])
            .unwrap_err()
            .to_string();
        assert!(error.contains("the position"), "{error}");
        // Odometry reads a child frame after the header: these bytes are too short for it.
        assert!(decode_ros1_pose(PoseMessage::Odometry, &data).is_err());
        assert_eq!(
            ros2_type_name("geometry_msgs/PoseStamped"),
            "geometry_msgs/msg/PoseStamped"
        );
    }

    #[test]
    fn bad_files_are_errors_naming_them() {
        let dir = std::env::temp_dir().join(format!("sitar-ros1-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.bag");
        for (bytes, message) in [
            (b"not a bag".to_vec(), "not a ROS 1 bag"),
            (MAGIC.to_vec(), "cut short"),
            (
                [MAGIC, &[4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0][..]].concat(),
                "without index_pos",
            ),
            (
                [MAGIC, &[4, 0, 0, 0, 9, 0, 0, 0, 0, 0, 0, 0][..]].concat(),
                "bad bag header field",
            ),
            (
                [
                    MAGIC,
                    &[22, 0, 0, 0, 18, 0, 0, 0],
                    b"index_pos=",
                    &u64::MAX.to_le_bytes(),
                    &[0, 0, 0, 0],
                ]
                .concat(),
                "outside the file",
            ),
        ] {
            std::fs::write(&path, &bytes).unwrap();
            let error = read_ros1_bag(&path).unwrap_err().to_string();
            assert!(
                error.contains("bad.bag") && error.contains(message),
                "{error}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
