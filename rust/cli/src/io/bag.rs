//! ROS bags as evo reads them: `bag` (ROS 1, the estimator's reader: uncompressed, bz2 and
//! lz4 chunks) and `bag2` (ROS 2: a bag directory, an `.mcap` or a `.db3` file). ROS 2
//! storages: MCAP (the estimator's reader: uncompressed, zstd and lz4 chunks) and sqlite3
//! (its `topics` and `messages` tables here, rusqlite, messages in stamp order as rosbags
//! yields them); rosbag2's zstd compression of whole files (`.mcap.zstd`, `.db3.zstd`) or of
//! each message (`compression_mode: message` in `metadata.yaml`). Topics may be evo's tf ids
//! (`/tf:map.base_link`).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use sitar_estimator::{
    BagTrajectory, PoseMessage, TfId, TopicMessages, read_mcap_from, read_mcap_topics,
    read_ros1_bag_topics, tf_trajectory, topic_trajectory,
};

use crate::io::console::Console;

/// The largest file a zstd-compressed bag file may expand to.
const MAX_FILE_BYTES: u64 = 4 << 30;
/// The largest message a zstd-compressed message may expand to.
const MAX_MESSAGE_BYTES: u64 = 256 << 20;

/// rosbag2's compression of a bag, from its `metadata.yaml`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum Compression {
    #[default]
    None,
    /// Each file is zstd-compressed (`NAME.mcap.zstd`).
    File,
    /// Each message's bytes are zstd-compressed.
    Message,
}

/// The compression `metadata.yaml` declares (its `compression_mode` and
/// `compression_format` keys; rosbag2 writes zstd only).
fn compression(dir: &Path) -> Result<Compression> {
    let path = dir.join("metadata.yaml");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Compression::None);
    };
    let value = |key: &str| {
        text.lines()
            .find_map(|l| l.trim().strip_prefix(key)?.strip_prefix(':'))
            .map(|v| v.trim().trim_matches(['\'', '"']).to_ascii_lowercase())
            .unwrap_or_default()
    };
    let (mode, format) = (value("compression_mode"), value("compression_format"));
    let compression = match mode.as_str() {
        "" | "none" => return Ok(Compression::None),
        "file" => Compression::File,
        "message" => Compression::Message,
        other => bail!(
            "{}: compression_mode {other} is not supported (rosbag2 writes file or message)",
            path.display()
        ),
    };
    if format != "zstd" {
        bail!(
            "{}: compression_format '{format}' is not supported (rosbag2 writes zstd)",
            path.display()
        );
    }
    Ok(compression)
}

/// zstd-decompresses `data`, at most `limit` bytes.
fn unzstd(data: impl Read, limit: u64, what: &str) -> Result<Vec<u8>> {
    let decoder =
        zstd::stream::read::Decoder::new(data).with_context(|| format!("{what}: zstd"))?;
    let mut out = Vec::new();
    decoder
        .take(limit + 1)
        .read_to_end(&mut out)
        .with_context(|| format!("{what}: zstd"))?;
    if out.len() as u64 > limit {
        bail!("{what}: expands to more than {limit} bytes");
    }
    Ok(out)
}

/// The storage files of a ROS 2 bag at `path` (a directory or one file).
fn bag2_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        return Ok(vec![path.to_owned()]);
    }
    let storage = |p: &Path| {
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
        name.is_some_and(|n| {
            [".mcap", ".db3", ".mcap.zstd", ".db3.zstd"]
                .iter()
                .any(|e| n.ends_with(e))
        })
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(path)
        .with_context(|| format!("{}: cannot list the bag", path.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| storage(p))
        .collect();
    files.sort();
    if files.is_empty() {
        bail!(
            "{}: a bag directory without .mcap or .db3 files",
            path.display()
        );
    }
    Ok(files)
}

/// Every topic of the ROS 2 bag at `path`, with the messages of the `wanted` ones.
pub fn read_bag2(path: &Path, wanted: &Wanted) -> Result<BTreeMap<String, TopicMessages>> {
    let wanted = |topic: &str| wanted.wants(topic);
    let compression = if path.is_dir() {
        compression(path)?
    } else {
        Compression::None
    };
    let mut topics: BTreeMap<String, TopicMessages> = BTreeMap::new();
    for file in &bag2_files(path)? {
        let name = file.to_string_lossy();
        let zstd_file = name.ends_with(".zstd");
        let sqlite = name.trim_end_matches(".zstd").ends_with(".db3");
        let read = if zstd_file || compression == Compression::File {
            let source = std::fs::File::open(file)
                .with_context(|| format!("{}: cannot read", file.display()))?;
            let bytes = unzstd(source, MAX_FILE_BYTES, &name)?;
            if sqlite {
                // SQLite opens files only: the expanded database goes to a temporary file.
                let mut temporary = tempfile::NamedTempFile::new()?;
                std::io::Write::write_all(&mut temporary, &bytes)?;
                read_sqlite3(temporary.path(), &wanted)
            } else {
                read_mcap_topics(&bytes, &wanted).map_err(anyhow::Error::from)
            }
        } else if sqlite {
            read_sqlite3(file, &wanted)
        } else {
            let source = std::fs::File::open(file)
                .with_context(|| format!("{}: cannot read", file.display()))?;
            // Streamed: a bag of many gigabytes is not read into memory. The reader asks for
            // each record apart: a buffer saves a system call per message.
            let source = std::io::BufReader::with_capacity(1 << 18, source);
            read_mcap_from(source, &wanted).map_err(anyhow::Error::from)
        };
        for (topic, part) in read.with_context(|| format!("{}", file.display()))? {
            let entry = topics.entry(topic.clone()).or_default();
            if entry.type_name.is_empty() {
                entry.type_name = part.type_name;
            }
            for (k, message) in part.messages.into_iter().enumerate() {
                let message = if compression == Compression::Message {
                    let what = format!("{name}: topic {topic}, message {}", k + 1);
                    unzstd(message.as_slice(), MAX_MESSAGE_BYTES, &what)?
                } else {
                    message
                };
                entry.messages.push(message);
            }
        }
    }
    Ok(topics)
}

/// The topics and messages of a ROS 2 bag's sqlite3 storage (rosbag2's `topics` and
/// `messages` tables), messages by stamp, of the `wanted` topics only.
fn read_sqlite3(
    path: &Path,
    wanted: &dyn Fn(&str) -> bool,
) -> Result<BTreeMap<String, TopicMessages>> {
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
    // The ids are the database's integers: the list is no injection.
    let ids: Vec<String> = names
        .iter()
        .filter(|(_, name)| wanted(name))
        .map(|(id, _)| id.to_string())
        .collect();
    let mut statement = db.prepare(&format!(
        "SELECT topic_id, data FROM messages WHERE topic_id IN ({}) ORDER BY timestamp, id",
        ids.join(",")
    ))?;
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
/// names it; a tf id (`/tf:map.base_link`) is looked up in the tf buffer; PointStamped gets
/// evo's warning.
pub fn trajectory(
    topics: &BTreeMap<String, TopicMessages>,
    topic: &str,
    bag: &str,
    console: &Console,
) -> Result<BagTrajectory> {
    if let Some(tf) = TfId::parse(topic).with_context(|| bag.to_owned())? {
        console.debug(&format!(
            "Loading trajectory of transform '{} to {}' from topic {} (static topic: {}).",
            tf.parent, tf.child, tf.topic, tf.static_topic
        ))?;
        return tf_trajectory(topics, &tf, topic).with_context(|| bag.to_owned());
    }
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

/// The topics whose messages a command reads: all, or those named (a tf id names its tf
/// and static topics).
pub enum Wanted {
    /// Every topic (`--all_topics`).
    All,
    /// These topics.
    Topics(std::collections::BTreeSet<String>),
}

impl Wanted {
    /// The topics of `names` (topics or tf ids).
    pub fn named<'a>(names: impl IntoIterator<Item = &'a String>) -> Self {
        let mut topics = std::collections::BTreeSet::new();
        for name in names {
            match TfId::parse(name) {
                Ok(Some(tf)) => topics.extend([tf.topic, tf.static_topic]),
                _ => {
                    topics.insert(name.clone());
                }
            }
        }
        Self::Topics(topics)
    }

    fn wants(&self, topic: &str) -> bool {
        match self {
            Wanted::All => true,
            Wanted::Topics(topics) => topics.contains(topic),
        }
    }
}

/// Reads a bag of evo's format `kind` (`bag`: ROS 1; `bag2`: ROS 2), the messages of the
/// `wanted` topics only, saying so as evo does.
pub fn open(
    kind: &str,
    bag: &str,
    wanted: &Wanted,
    console: &Console,
) -> Result<BTreeMap<String, TopicMessages>> {
    console.debug(&format!("Opening bag file {bag}"))?;
    let path = Path::new(bag);
    if !path.exists() {
        bail!("{bag}: cannot read: the file does not exist");
    }
    if kind == "bag" {
        Ok(read_ros1_bag_topics(path, &|topic| wanted.wants(topic))?)
    } else {
        read_bag2(path, wanted)
    }
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
