//! ROS 2 bags (`bag2`, evo's `evo_ape bag2 BAG REF_TOPIC EST_TOPIC`): a bag directory (its
//! `.mcap` or `.db3` files), an `.mcap` file or a `.db3` file. MCAP is read by the
//! estimator's reader; the sqlite3 storage's `topics` and `messages` tables here (rusqlite),
//! messages in stamp order as rosbags (evo's reader) yields them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use sitar_estimator::{BagTrajectory, PoseMessage, TopicMessages, read_mcap, topic_trajectory};

use crate::console::Console;

/// Every topic of the ROS 2 bag at `path`.
pub fn read_bag2(path: &Path) -> Result<BTreeMap<String, TopicMessages>> {
    let files: Vec<PathBuf> = if path.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .with_context(|| format!("{}: cannot list the bag", path.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "mcap" || e == "db3"))
            .collect();
        files.sort();
        if files.is_empty() {
            bail!(
                "{}: a bag directory without .mcap or .db3 files",
                path.display()
            );
        }
        files
    } else {
        vec![path.to_owned()]
    };
    let mut topics: BTreeMap<String, TopicMessages> = BTreeMap::new();
    for file in &files {
        let read = if file.extension().is_some_and(|e| e == "db3") {
            read_sqlite3(file)
        } else {
            let bytes =
                std::fs::read(file).with_context(|| format!("{}: cannot read", file.display()))?;
            read_mcap(&bytes).map_err(anyhow::Error::from)
        };
        for (topic, part) in read.with_context(|| format!("{}", file.display()))? {
            let entry = topics.entry(topic).or_default();
            if entry.type_name.is_empty() {
                entry.type_name = part.type_name;
            }
            entry.messages.extend(part.messages);
        }
    }
    Ok(topics)
}

/// The topics and messages of a ROS 2 bag's sqlite3 storage (rosbag2's `topics` and
/// `messages` tables), messages by stamp.
fn read_sqlite3(path: &Path) -> Result<BTreeMap<String, TopicMessages>> {
    let flags = rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY;
    let db = rusqlite::Connection::open_with_flags(path, flags)?;
    let mut names = BTreeMap::new();
    let mut topics: BTreeMap<String, TopicMessages> = BTreeMap::new();
    let mut statement = db.prepare("SELECT id, name, type FROM topics")?;
    let rows = statement.query_map([], |r| {
        Ok((
            r.get::<_, i64>(0)?,
            r.get::<_, String>(1)?,
            r.get::<_, String>(2)?,
        ))
    })?;
    for row in rows {
        let (id, name, type_name) = row?;
        topics.entry(name.clone()).or_default().type_name = type_name;
        names.insert(id, name);
    }
    let mut statement = db.prepare("SELECT topic_id, data FROM messages ORDER BY timestamp, id")?;
    let rows = statement.query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, Vec<u8>>(1)?)))?;
    for row in rows {
        let (id, data) = row?;
        let Some(name) = names.get(&id) else {
            bail!("a message of topic id {id}, which the topics table does not list");
        };
        topics.entry(name.clone()).or_default().messages.push(data);
    }
    Ok(topics)
}

/// The trajectory of `topic` in `topics` (read from `bag`), named by its topic as evo
/// names it; PointStamped gets evo's warning.
pub fn trajectory(
    topics: &BTreeMap<String, TopicMessages>,
    topic: &str,
    bag: &str,
    console: &Console,
) -> Result<BagTrajectory> {
    let Some(messages) = topics.get(topic) else {
        bail!("{bag}: no messages for topic '{topic}' in bag");
    };
    if PoseMessage::from_type_name(&messages.type_name) == Some(PoseMessage::PointStamped) {
        console.warn(
            "geometry_msgs/PointStamped does not contain rotation, evo will use unit quaternion. Note that rotation metrics will be invalid and RPE will only be valid with point_distance metric.",
        );
    }
    let read = topic_trajectory(topic, messages).with_context(|| bag.to_owned())?;
    console.debug(&format!(
        "Loaded {} {} messages of topic: {topic}",
        read.trajectory.len(),
        messages.type_name
    ))?;
    Ok(read)
}

/// [`read_bag2`], saying so as evo does.
pub fn open(bag: &str, console: &Console) -> Result<BTreeMap<String, TopicMessages>> {
    console.debug(&format!("Opening bag file {bag}"))?;
    read_bag2(Path::new(bag))
}

/// The topics of `topics` with a pose type evo reads and at least one message, sorted.
pub fn supported_topics(topics: &BTreeMap<String, TopicMessages>) -> Vec<String> {
    topics
        .iter()
        .filter(|(_, m)| {
            PoseMessage::from_type_name(&m.type_name).is_some() && !m.messages.is_empty()
        })
        .map(|(t, _)| t.clone())
        .collect()
}
