//! Local copies of the recording parts this instance stored, kept in `DATA/tmp` (emptied at
//! start), so a recording it received whole is checked from its own copy and published by a
//! server-side copy of the part: no byte of it is read back from the bucket or sent twice.
//! A copy is used only while its part's entity tag is the stored one (another instance may
//! have replaced the part). At most [`LOCAL_PARTS`] copies; the oldest go first.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use object_store::path::Path as Key;

/// Copies kept at most.
pub(crate) const LOCAL_PARTS: usize = 16;

/// One part's local copy.
struct Copy {
    key: Key,
    file: PathBuf,
    e_tag: String,
}

/// The copies, oldest first.
#[derive(Default)]
pub(crate) struct LocalParts(Mutex<VecDeque<Copy>>);

impl LocalParts {
    fn lock(&self) -> std::sync::MutexGuard<'_, VecDeque<Copy>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Keeps `file` (which this takes over) as the copy of the part at `key`.
    pub fn keep(&self, key: Key, file: PathBuf, e_tag: String) {
        let mut copies = self.lock();
        copies.retain(|c| {
            let same = c.key == key;
            if same {
                let _ = std::fs::remove_file(&c.file);
            }
            !same
        });
        copies.push_back(Copy { key, file, e_tag });
        while copies.len() > LOCAL_PARTS {
            if let Some(old) = copies.pop_front() {
                let _ = std::fs::remove_file(&old.file);
            }
        }
    }

    /// The local copy of the part at `key` whose stored entity tag is `e_tag`, linked (or
    /// copied) to `to`; whether it was.
    pub fn link(&self, key: &Key, e_tag: Option<&str>, to: &Path) -> bool {
        let copies = self.lock();
        let Some(copy) = copies
            .iter()
            .find(|c| &c.key == key && Some(c.e_tag.as_str()) == e_tag)
        else {
            return false;
        };
        std::fs::hard_link(&copy.file, to).is_ok() || std::fs::copy(&copy.file, to).is_ok()
    }

    /// Forgets the copies of the parts under `folder`.
    pub fn forget_under(&self, folder: &Key) {
        self.lock().retain(|c| {
            let under = c.key.prefix_matches(folder);
            if under {
                let _ = std::fs::remove_file(&c.file);
            }
            !under
        });
    }
}
