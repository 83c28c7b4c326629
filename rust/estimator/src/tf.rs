//! Trajectories of tf transforms, as evo's `TfCache` looks them up: a topic id
//! `/tf:PARENT.CHILD` (or `/tf:PARENT.CHILD:/tf_static`) names the transform from CHILD to
//! PARENT; the `tf2_msgs/msg/TFMessage`s of the tf topic (and of the static topic, when the
//! bag has it) fill a buffer, and the transform is looked up as tf2 does (per edge: the two
//! stamps around the time, translation interpolated linearly, rotation by tf2's slerp; the
//! chain composed through the frames' common ancestor) from the first transform's stamp in
//! steps of 0.1 s (evo's default `tf_cache_lookup_frequency` of 10 Hz) up to the latest
//! time every edge of the chain has. Times a dynamic edge does not cover are skipped, as evo
//! skips tf2's extrapolation errors.

use std::collections::{BTreeMap, HashMap};

use glam::{DQuat, DVec3};
use serde::Deserialize;

use crate::pose_messages::{StampedTransform, quaternion, vector};
use crate::ros1::Ros1Reader;
use crate::rosbag::decode_cdr;
use crate::{BagTrajectory, Encoding, Error, TimeUnit, TopicMessages, Trajectory};

/// evo's default lookup step (1 / `tf_cache_lookup_frequency` of 10 Hz), in ns.
pub const TF_LOOKUP_STEP_NS: i64 = 100_000_000;

/// The message type of tf topics.
pub const TF_MESSAGE_TYPE: &str = "tf2_msgs/msg/TFMessage";

/// A parsed tf topic id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TfId {
    /// The tf topic (`/tf`).
    pub topic: String,
    /// The parent (target) frame.
    pub parent: String,
    /// The child (source) frame.
    pub child: String,
    /// The static transforms' topic (`/tf_static` unless given).
    pub static_topic: String,
}

impl TfId {
    /// Parses evo's `/tf:map.base_link(:/tf_static)`; `None` when `id` is no tf id (a plain
    /// topic), an error naming what is missing when it looks like one but is malformed.
    pub fn parse(id: &str) -> Result<Option<Self>, Error> {
        let Some((topic, rest)) = id.split_once(':') else {
            return Ok(None);
        };
        let (frames, static_topic) = match rest.rsplit_once(':') {
            Some((frames, static_topic)) => (frames, static_topic),
            None => (rest, "/tf_static"),
        };
        let (parent, child) = frames.split_once('.').unwrap_or((frames, ""));
        let valid_topic = |t: &str| {
            t.len() >= 2
                && t.chars()
                    .all(|c| c == '/' || c == '_' || c.is_ascii_alphanumeric())
        };
        let malformed = |what: String| {
            Error::InvalidArgument(format!(
                "tf id '{id}' malformed: {what}; it should look like /tf:map.base_footprint(:/tf_static)"
            ))
        };
        if !valid_topic(topic) {
            return Err(malformed(format!("{topic} is not a valid topic name")));
        }
        if !valid_topic(static_topic) {
            return Err(malformed(format!(
                "{static_topic} is not a valid topic name"
            )));
        }
        if parent.is_empty() {
            return Err(malformed("the parent frame id is missing".into()));
        }
        if child.is_empty() {
            return Err(malformed("the child frame id is missing".into()));
        }
        Ok(Some(Self {
            topic: topic.to_owned(),
            parent: parent.to_owned(),
            child: child.to_owned(),
            static_topic: static_topic.to_owned(),
        }))
    }
}

/// One transform of a tf message: the pose of `child` in `parent` at `stamp_ns`.
#[derive(Debug, Clone, PartialEq)]
pub struct TfTransform {
    /// The header stamp (ns).
    pub stamp_ns: i64,
    /// `header.frame_id`.
    pub parent: String,
    /// `child_frame_id`.
    pub child: String,
    /// The translation.
    pub translation: DVec3,
    /// The rotation (as written).
    pub rotation: DQuat,
}

impl From<StampedTransform> for TfTransform {
    fn from(t: StampedTransform) -> Self {
        Self {
            stamp_ns: t.header.stamp.ns(),
            parent: t.header.frame_id,
            child: t.child_frame_id,
            translation: vector(t.translation),
            rotation: quaternion(t.rotation),
        }
    }
}

#[derive(Deserialize)]
struct TfMessage {
    transforms: Vec<StampedTransform>,
}

/// Decodes one `tf2_msgs/msg/TFMessage`.
pub fn decode_tf_message(encoding: Encoding, data: &[u8]) -> Result<Vec<TfTransform>, Error> {
    match encoding {
        Encoding::Cdr => {
            let message: TfMessage = decode_cdr(data)?;
            Ok(message.transforms.into_iter().map(Into::into).collect())
        }
        Encoding::Ros1 => {
            let mut r = Ros1Reader::new(data);
            let n = r.u32("the transform count")? as usize;
            // Each transform takes at least 89 bytes: the count cannot ask for more.
            let mut out = Vec::with_capacity(n.min(data.len() / 89));
            for _ in 0..n {
                out.push(r.transform_stamped()?.into());
            }
            Ok(out)
        }
    }
}

#[derive(Clone, Copy)]
struct Rigid {
    t: DVec3,
    q: DQuat,
}

impl Rigid {
    const IDENTITY: Self = Self {
        t: DVec3::ZERO,
        q: DQuat::IDENTITY,
    };

    /// `self ∘ inner` (apply `inner` first).
    fn then_in(self, inner: Rigid) -> Rigid {
        Rigid {
            t: self.q * inner.t + self.t,
            q: self.q * inner.q,
        }
    }

    fn inverse(self) -> Rigid {
        let q = self.q.inverse();
        Rigid { t: q * -self.t, q }
    }
}

/// tf2's `Quaternion::slerp` (shortest path; no normalisation).
fn tf2_slerp(a: DQuat, b: DQuat, t: f64) -> DQuat {
    let dot = a.dot(b);
    let s = (a.length_squared() * b.length_squared()).sqrt();
    let theta = (dot.abs() / s).clamp(-1.0, 1.0).acos();
    if theta == 0.0 {
        return a;
    }
    let d = 1.0 / theta.sin();
    let (s0, s1) = (((1.0 - t) * theta).sin(), (t * theta).sin());
    let b = if dot < 0.0 { -b } else { b };
    DQuat::from_xyzw(
        (a.x * s0 + b.x * s1) * d,
        (a.y * s0 + b.y * s1) * d,
        (a.z * s0 + b.z * s1) * d,
        (a.w * s0 + b.w * s1) * d,
    )
}

/// One frame's transforms to its parent, by stamp.
#[derive(Default)]
struct Edge {
    /// (stamp, parent, transform), sorted by stamp, one per stamp (the first kept, as tf2).
    entries: Vec<(i64, String, Rigid)>,
}

impl Edge {
    /// The transform at `t` and the parent then; `None` outside the stamps (tf2's
    /// extrapolation).
    fn at(&self, t: i64) -> Option<(&str, Rigid)> {
        let after = self.entries.partition_point(|e| e.0 <= t);
        let (t1, parent, one) = self.entries.get(after.checked_sub(1)?)?;
        if *t1 == t {
            return Some((parent, *one));
        }
        let (t2, _, two) = self.entries.get(after)?;
        let ratio = (t - t1) as f64 / (t2 - t1) as f64;
        let translation = one.t * (1.0 - ratio) + two.t * ratio;
        Some((
            parent,
            Rigid {
                t: translation,
                q: tf2_slerp(one.q, two.q, ratio),
            },
        ))
    }

    fn latest(&self) -> i64 {
        self.entries.last().map_or(0, |e| e.0)
    }

    fn parent(&self) -> &str {
        self.entries.last().map_or("", |e| e.1.as_str())
    }
}

/// The tf buffer of one bag: dynamic edges by child frame, static ones beside them.
#[derive(Default)]
pub struct TfBuffer {
    dynamic: HashMap<String, Edge>,
    fixed: HashMap<String, (String, Rigid)>,
    /// The stamp of the first transform of the tf topic (evo's lookup start).
    first_stamp: Option<i64>,
}

impl TfBuffer {
    /// Adds the transforms of the tf topic (`is_static` false) or the static topic.
    pub fn add(&mut self, transforms: Vec<TfTransform>, is_static: bool) {
        for t in transforms {
            let rigid = Rigid {
                t: t.translation,
                q: t.rotation,
            };
            if is_static {
                self.fixed.insert(t.child, (t.parent, rigid));
                continue;
            }
            self.first_stamp.get_or_insert(t.stamp_ns);
            let edge = self.dynamic.entry(t.child).or_default();
            let at = edge.entries.partition_point(|e| e.0 < t.stamp_ns);
            if edge.entries.get(at).is_none_or(|e| e.0 != t.stamp_ns) {
                edge.entries.insert(at, (t.stamp_ns, t.parent, rigid));
            }
        }
    }

    /// The frames from `frame` up to its root (`frame` first), by the latest parents.
    fn chain(&self, frame: &str) -> Vec<String> {
        let mut chain = vec![frame.to_owned()];
        while chain.len() <= 10_000 {
            let last = chain.last().map(String::as_str).unwrap_or_default();
            let parent = match (self.dynamic.get(last), self.fixed.get(last)) {
                (Some(edge), _) => edge.parent().to_owned(),
                (None, Some((parent, _))) => parent.clone(),
                (None, None) => break,
            };
            if chain.contains(&parent) {
                break;
            }
            chain.push(parent);
        }
        chain
    }

    /// The frames of `frame`'s chain below `ancestor`.
    fn below<'c>(chain: &'c [String], ancestor: &str) -> &'c [String] {
        let end = chain
            .iter()
            .position(|f| f == ancestor)
            .unwrap_or(chain.len());
        &chain[..end]
    }

    /// The common ancestor of `parent` and `child`, or an error naming both frames.
    fn common_ancestor(&self, parent: &str, child: &str) -> Result<String, Error> {
        let known = |f: &str| {
            self.dynamic.contains_key(f)
                || self.fixed.contains_key(f)
                || self.dynamic.values().any(|e| e.parent() == f)
                || self.fixed.values().any(|(p, _)| p == f)
        };
        for frame in [parent, child] {
            if !known(frame) {
                return Err(Error::InvalidArgument(format!(
                    "Could not load trajectory: \"{frame}\" passed to lookupTransform argument {} does not exist (tf frames {parent} and {child})",
                    if frame == parent {
                        "target_frame"
                    } else {
                        "source_frame"
                    }
                )));
            }
        }
        let up = self.chain(parent);
        self.chain(child)
            .into_iter()
            .find(|f| up.contains(f))
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "Could not load trajectory: could not find a connection between '{parent}' and '{child}' because they are not part of the same tree"
                ))
            })
    }

    /// The transform from `frame` up to `ancestor` at `t`; `None` when an edge has no data
    /// around `t`.
    fn to_ancestor(&self, chain: &[String], t: i64) -> Option<Rigid> {
        let mut total = Rigid::IDENTITY;
        for frame in chain {
            let step = match (self.dynamic.get(frame), self.fixed.get(frame)) {
                (Some(edge), _) => edge.at(t)?.1,
                (None, Some((_, rigid))) => *rigid,
                (None, None) => return None,
            };
            total = step.then_in(total);
        }
        Some(total)
    }

    /// The latest time all dynamic edges between the frames have (0 when all are static).
    fn latest_common_time(&self, parent_chain: &[String], child_chain: &[String]) -> i64 {
        parent_chain
            .iter()
            .chain(child_chain)
            .filter_map(|f| self.dynamic.get(f).map(Edge::latest))
            .min()
            .unwrap_or(0)
    }

    /// The trajectory of `child` in `parent`, as evo's `TfCache.get_trajectory`.
    pub fn trajectory(&self, id: &TfId, name: &str) -> Result<BagTrajectory, Error> {
        let ancestor = self.common_ancestor(&id.parent, &id.child)?;
        let parent_chain = self.chain(&id.parent);
        let child_chain = self.chain(&id.child);
        let parent_chain = Self::below(&parent_chain, &ancestor);
        let child_chain = Self::below(&child_chain, &ancestor);
        let latest = self.latest_common_time(parent_chain, child_chain);
        let start = self.first_stamp.unwrap_or(0);
        let mut times = Vec::new();
        if latest < start {
            times.push(latest);
        } else {
            let mut t = start;
            while t <= latest && times.len() < 100_000_000 {
                times.push(t);
                t += TF_LOOKUP_STEP_NS;
            }
        }
        let mut out = Trajectory {
            time_unit: TimeUnit::RosStamp,
            ..Trajectory::default()
        };
        for t in times {
            // Time 0 asks tf2 for the latest transforms.
            let at = if t == 0 { latest } else { t };
            let (Some(up), Some(down)) = (
                self.to_ancestor(child_chain, at),
                self.to_ancestor(parent_chain, at),
            ) else {
                continue;
            };
            let pose = down.inverse().then_in(up);
            out.stamps.push(t);
            out.positions.push(pose.t);
            out.orientations.push(pose.q);
        }
        if out.stamps.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "{name}: no time at which the transform from {} to {} can be looked up",
                id.child, id.parent
            )));
        }
        let mut quaternions_off_unit = 0;
        for q in &mut out.orientations {
            let norm = q.length();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(Error::InvalidArgument(format!(
                    "{name}: a transform with a zero or non-finite rotation"
                )));
            }
            quaternions_off_unit += usize::from((norm - 1.0).abs() > 1e-8 + 1e-5);
            *q /= norm;
        }
        Ok(BagTrajectory {
            trajectory: out,
            frame_id: id.parent.clone(),
            quaternions_off_unit,
        })
    }
}

/// The trajectory of the tf id `id` (parsed as `tf`) from a bag's topics: the tf topic, and
/// the static topic when the bag has it. Errors name the topics and frames.
pub fn tf_trajectory(
    topics: &BTreeMap<String, TopicMessages>,
    tf: &TfId,
    id: &str,
) -> Result<BagTrajectory, Error> {
    let Some(dynamic) = topics.get(&tf.topic) else {
        return Err(Error::InvalidArgument(format!(
            "no messages for topic {} in bag",
            tf.topic
        )));
    };
    let mut buffer = TfBuffer::default();
    let sources = [(Some(dynamic), &tf.topic, false)].into_iter().chain([(
        topics.get(&tf.static_topic),
        &tf.static_topic,
        true,
    )]);
    for (messages, topic, is_static) in sources {
        let Some(messages) = messages else { continue };
        if messages.type_name != TF_MESSAGE_TYPE {
            return Err(Error::InvalidArgument(format!(
                "Expected {TF_MESSAGE_TYPE} message type for topic {topic}, got: {}",
                messages.type_name
            )));
        }
        for (k, data) in messages.messages.iter().enumerate() {
            let transforms = decode_tf_message(messages.encoding, data).map_err(|e| {
                Error::InvalidArgument(format!(
                    "topic {topic} ({TF_MESSAGE_TYPE}), message {}: {e}",
                    k + 1
                ))
            })?;
            buffer.add(transforms, is_static);
        }
    }
    buffer.trajectory(tf, id)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn transform(stamp_s: f64, parent: &str, child: &str, x: f64, yaw: f64) -> TfTransform {
        TfTransform {
            stamp_ns: (stamp_s * 1e9).round() as i64,
            parent: parent.into(),
            child: child.into(),
            translation: DVec3::new(x, 0.0, 0.0),
            rotation: DQuat::from_rotation_z(yaw),
        }
    }

    #[test]
    fn parses_evo_tf_ids() {
        let id = TfId::parse("/tf:map.base_link").unwrap().unwrap();
        assert_eq!(
            (id.topic.as_str(), id.parent.as_str(), id.child.as_str()),
            ("/tf", "map", "base_link")
        );
        assert_eq!(id.static_topic, "/tf_static");
        let id = TfId::parse("/tf:odom.base.link:/my_static")
            .unwrap()
            .unwrap();
        assert_eq!(
            (id.child.as_str(), id.static_topic.as_str()),
            ("base.link", "/my_static")
        );
        assert_eq!(TfId::parse("/odom").unwrap(), None);
        let error = TfId::parse("/tf:map").unwrap_err().to_string();
        assert!(error.contains("child frame id is missing"), "{error}");
    }

    /// Analytic case: odom→base moves along x at 1 m/s and turns at 0.1 rad/s, sampled
    /// every 0.25 s; map→odom is static, 2 m along y. Between samples tf2 interpolates
    /// linearly and by slerp, which is exact for this motion.
    #[test]
    fn chains_static_and_interpolated_transforms() {
        let mut buffer = TfBuffer::default();
        let samples: Vec<TfTransform> = (0..9)
            .map(|k| {
                let t = 10.0 + 0.25 * f64::from(k);
                transform(t, "odom", "base", t - 10.0, 0.1 * (t - 10.0))
            })
            .collect();
        buffer.add(samples, false);
        let mut fixed = transform(0.0, "map", "odom", 0.0, 0.0);
        fixed.translation = DVec3::new(0.0, 2.0, 0.0);
        buffer.add(vec![fixed], true);
        let id = TfId::parse("/tf:map.base").unwrap().unwrap();
        let read = buffer.trajectory(&id, "/tf:map.base").unwrap();
        let t = &read.trajectory;
        // 10.0, 10.1, …, 12.0 s: 21 lookups.
        assert_eq!(t.len(), 21);
        for k in 0..t.len() {
            let s = (t.stamps[k] - 10_000_000_000) as f64 / 1e9;
            assert!((t.positions[k] - DVec3::new(s, 2.0, 0.0)).length() < 1e-12);
            let want = DQuat::from_rotation_z(0.1 * s);
            assert!(t.orientations[k].angle_between(want) < 1e-9, "{k}");
        }
        assert_eq!(read.frame_id, "map");
        // The other way round: the inverse.
        let id = TfId::parse("/tf:base.map").unwrap().unwrap();
        let back = buffer.trajectory(&id, "x").unwrap().trajectory;
        assert!((back.positions[0] - DVec3::new(0.0, -2.0, 0.0)).length() < 1e-12);
        // Unknown frames are named.
        let id = TfId::parse("/tf:map.camera").unwrap().unwrap();
        let error = buffer.trajectory(&id, "x").unwrap_err().to_string();
        assert!(
            error.contains("\"camera\"") && error.contains("does not exist"),
            "{error}"
        );
    }

    #[test]
    fn decodes_ros1_tf_messages_and_bounds_counts() {
        let mut data = 1u32.to_le_bytes().to_vec();
        data.extend([0; 4]); // seq
        data.extend(3u32.to_le_bytes());
        data.extend(4u32.to_le_bytes());
        data.extend(3u32.to_le_bytes());
        data.extend(b"map");
        data.extend(4u32.to_le_bytes());
        data.extend(b"base");
        for v in [1.0f64, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0] {
            data.extend(v.to_le_bytes());
        }
        let t = decode_tf_message(Encoding::Ros1, &data).unwrap();
        assert_eq!(t.len(), 1);
        assert_eq!(
            (t[0].stamp_ns, t[0].parent.as_str(), t[0].child.as_str()),
            (3_000_000_004, "map", "base")
        );
        let mut huge = data.clone();
        huge[..4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_tf_message(Encoding::Ros1, &huge).is_err());
    }
}
