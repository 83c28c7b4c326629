//! Handles are ids in a map, never raw pointers: a stale, freed or garbage id
//! is an error, not undefined behaviour.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, PoisonError, RwLock};

use crate::error::Error;

/// An opaque handle to a native object; 0 is never valid.
pub type SitarHandle = u64;

/// One counter for every kind, so an id is never reused, not even by another kind.
static NEXT: AtomicU64 = AtomicU64::new(1);

/// Ids are the counter scrambled by splitmix64 (a bijection), so small garbage
/// numbers such as 1, 2, 3 are not live handles and ids hash well as they are.
fn next_id() -> SitarHandle {
    loop {
        let mut z = NEXT
            .fetch_add(1, Ordering::Relaxed)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        // Also keep ids within i64::MAX so Kotlin/C# see them as positive longs.
        z &= i64::MAX as u64;
        if z != 0 {
            return z;
        }
    }
}

/// The ids are already uniformly mixed: hashing them again is wasted time.
#[derive(Default)]
pub(crate) struct IdHasher(u64);

impl Hasher for IdHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 << 8) | u64::from(b);
        }
    }
    fn write_u64(&mut self, n: u64) {
        self.0 = n;
    }
}

/// Live objects of one kind.
pub(crate) struct Registry<T> {
    kind: &'static str,
    map: RwLock<HashMap<SitarHandle, Arc<T>, BuildHasherDefault<IdHasher>>>,
}

impl<T> Registry<T> {
    pub(crate) fn new(kind: &'static str) -> Self {
        Registry {
            kind,
            map: RwLock::new(HashMap::default()),
        }
    }

    pub(crate) fn insert(&self, value: T) -> SitarHandle {
        let id = next_id();
        self.map
            .write()
            .unwrap_or_else(PoisonError::into_inner)
            .insert(id, Arc::new(value));
        id
    }

    pub(crate) fn get(&self, handle: SitarHandle) -> Result<Arc<T>, Error> {
        self.map
            .read()
            .unwrap_or_else(PoisonError::into_inner)
            .get(&handle)
            .cloned()
            .ok_or(Error::InvalidHandle {
                kind: self.kind,
                handle,
            })
    }

    /// Runs `f` on the object while holding the map's read lock.
    pub(crate) fn with<R>(&self, handle: SitarHandle, f: impl FnOnce(&T) -> R) -> Result<R, Error> {
        let map = self.map.read().unwrap_or_else(PoisonError::into_inner);
        let value = map.get(&handle).ok_or(Error::InvalidHandle {
            kind: self.kind,
            handle,
        })?;
        Ok(f(value))
    }

    pub(crate) fn remove(&self, handle: SitarHandle) -> Result<Arc<T>, Error> {
        self.map
            .write()
            .unwrap_or_else(PoisonError::into_inner)
            .remove(&handle)
            .ok_or(Error::InvalidHandle {
                kind: self.kind,
                handle,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_nonzero_and_positive() {
        let mut seen = std::collections::HashSet::new();
        for _ in 0..10_000 {
            let id = next_id();
            assert!(id != 0 && id <= i64::MAX as u64);
            assert!(seen.insert(id));
        }
    }

    #[test]
    fn freed_and_garbage_handles_are_errors() {
        let r = Registry::new("thing");
        let h = r.insert(5_i32);
        assert_eq!(*r.get(h).unwrap(), 5);
        assert!(r.remove(h).is_ok());
        for bad in [h, 0, 1, 2, u64::MAX] {
            let err = r.get(bad).unwrap_err();
            assert!(matches!(err, Error::InvalidHandle { kind: "thing", handle } if handle == bad));
        }
        assert!(r.remove(h).is_err());
    }
}
