//! The playback device's logger: every frame's pose, written as TUM text.

use std::path::Path;

use crate::{Convention, Error, Pose};

/// Logs the pose of every frame during a playback trial and writes the TUM file
/// (`trajectory_N.txt`, integer nanoseconds) the backend estimates from.
///
/// Poses are written as given, in the logger's convention (the error estimate only uses
/// relative motion, which a Unity↔ARCore reflection preserves).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaybackLogger {
    convention: Convention,
    stamps: Vec<i64>,
    poses: Vec<Pose>,
}

impl PlaybackLogger {
    /// An empty logger for poses in `convention`.
    pub fn new(convention: Convention) -> Self {
        // About ten minutes at 30 fps without regrowth.
        Self {
            convention,
            stamps: Vec::with_capacity(1 << 14),
            poses: Vec::with_capacity(1 << 14),
        }
    }

    /// The convention of the logged poses.
    pub fn convention(&self) -> Convention {
        self.convention
    }

    /// Logs one frame. Timestamps must increase strictly; poses must be finite.
    pub fn log(&mut self, t_ns: i64, pose: Pose) -> Result<(), Error> {
        let pose = pose.validated("pose")?;
        if let Some(&last) = self.stamps.last()
            && t_ns <= last
        {
            return Err(Error::arg(
                "t_ns",
                format!("{t_ns} does not follow the previous frame ({last})"),
            ));
        }
        self.stamps.push(t_ns);
        self.poses.push(pose);
        Ok(())
    }

    /// Number of logged frames.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// Whether nothing was logged yet.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// The TUM text: `t x y z qx qy qz qw` per frame, `t` in integer nanoseconds.
    pub fn to_tum(&self) -> String {
        crate::tum::to_tum(self.stamps.iter().copied().zip(self.poses.iter()))
    }

    /// Writes [`PlaybackLogger::to_tum`] to `path`, whole or not at all: the
    /// text goes to `path` + `.part` first and is renamed into place, so the
    /// backend polling the folder over adb never pulls a half-written trial.
    pub fn write(&self, path: &Path) -> Result<(), Error> {
        let mut partial = path.as_os_str().to_owned();
        partial.push(".part");
        let partial = std::path::PathBuf::from(partial);
        std::fs::write(&partial, self.to_tum()).map_err(|e| Error::io(&partial, e))?;
        std::fs::rename(&partial, path).map_err(|e| Error::io(path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DQuat, DVec3};

    #[test]
    fn logs_every_frame_and_writes_tum() {
        let mut log = PlaybackLogger::new(Convention::Arcore);
        for i in 0..25i64 {
            let pose = Pose::new(
                DVec3::new(i as f64 * 0.01, 1.5, 0.0),
                DQuat::from_rotation_y(i as f64 * 0.01),
            );
            log.log(1_000_000_000 + i * 33_333_333, pose).unwrap();
        }
        assert_eq!(log.len(), 25);
        assert!(log.log(1_000_000_000, Pose::IDENTITY).is_err());
        let text = log.to_tum();
        assert_eq!(text.lines().count(), 25);
        let parsed = crate::tum::parse_tum_ns(&text, "trajectory_0.txt").unwrap();
        assert_eq!(parsed[24].0, 1_000_000_000 + 24 * 33_333_333);
        assert_eq!(parsed[24].1.position, DVec3::new(0.24, 1.5, 0.0));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trajectory_0.txt");
        log.write(&path).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
        // Only the finished file is left: no `.part` for a poller to pick up.
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["trajectory_0.txt"]);
        assert!(matches!(
            log.write(&dir.path().join("missing/x.txt")),
            Err(Error::Io { .. })
        ));
    }
}
