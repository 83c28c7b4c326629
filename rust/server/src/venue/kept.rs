//! A session's contribution to its venue's map as the metadata store keeps it
//! (`venue_contributions.body`): its listing (alignment or why it is not in the map) and, in
//! the venue frame, each sub-trajectory's midpoint, camera heading, surface point and error.
//! Little-endian binary, about 70 bytes a sub-trajectory, so a map of a thousand sessions
//! reads a few megabytes and decodes them in milliseconds; a body this version cannot read
//! (another format version, a truncated value) is `None` and the contribution is computed
//! again from the session's files.

use glam::DVec3;
use sitar_core::Convention;
use sitar_core::venue::{Alignment, Contribution, Sample};

/// The format's tag and version: a later format takes the next, and older bodies are
/// recomputed.
const MAGIC: &[u8; 4] = b"SVC1";

const IN_MAP: u8 = 0;
const EXCLUDED: u8 = 1;
const NOT_ALIGNED: u8 = 2;

/// The kept form of `contribution`.
pub(crate) fn encode(contribution: &Contribution) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + 72 * contribution.samples().len());
    out.extend_from_slice(MAGIC);
    match contribution {
        Contribution::InMap {
            session,
            convention,
            alignment,
            samples,
        } => {
            out.push(IN_MAP);
            text(&mut out, session);
            out.push(match convention {
                Convention::Unity => 0,
                Convention::Arcore => 1,
            });
            put_alignment(&mut out, alignment);
            out.extend_from_slice(&(samples.len() as u32).to_le_bytes());
            for s in samples {
                out.extend_from_slice(&s.subtrajectory.to_le_bytes());
                vector(&mut out, s.position);
                match s.heading_rad {
                    Some(h) => {
                        out.push(1);
                        out.extend_from_slice(&h.to_le_bytes());
                    }
                    None => out.push(0),
                }
                match s.surface {
                    Some(p) => {
                        out.push(1);
                        vector(&mut out, p);
                    }
                    None => out.push(0),
                }
                out.extend_from_slice(&s.error_m.to_le_bytes());
            }
        }
        Contribution::Excluded {
            session,
            alignment,
            reason,
        } => {
            out.push(EXCLUDED);
            text(&mut out, session);
            put_alignment(&mut out, alignment);
            text(&mut out, reason);
        }
        Contribution::NotAligned { session, reason } => {
            out.push(NOT_ALIGNED);
            text(&mut out, session);
            text(&mut out, reason);
        }
    }
    out
}

/// The contribution kept as `bytes`; `None` when they are not [`encode`]'s of this version
/// (or have bytes left over).
pub(crate) fn decode(bytes: &[u8]) -> Option<Contribution> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(4)? != MAGIC {
        return None;
    }
    let contribution = match r.u8()? {
        IN_MAP => {
            let session = r.text()?;
            let convention = match r.u8()? {
                0 => Convention::Unity,
                1 => Convention::Arcore,
                _ => return None,
            };
            let alignment = r.alignment()?;
            let n = r.u32()? as usize;
            // Each sample takes at least 46 bytes: a count beyond what is left is garbage.
            if n > (bytes.len() - r.at) / 46 {
                return None;
            }
            let mut samples = Vec::with_capacity(n);
            for _ in 0..n {
                let subtrajectory = r.u32()?;
                let position = r.vector()?;
                let heading_rad = r.option(|r| r.f64())?;
                let surface = r.option(|r| r.vector())?;
                let error_m = r.f64()?;
                samples.push(Sample {
                    subtrajectory,
                    position,
                    heading_rad,
                    surface,
                    error_m,
                });
            }
            Contribution::InMap {
                session,
                convention,
                alignment,
                samples,
            }
        }
        EXCLUDED => Contribution::Excluded {
            session: r.text()?,
            alignment: r.alignment()?,
            reason: r.text()?,
        },
        NOT_ALIGNED => Contribution::NotAligned {
            session: r.text()?,
            reason: r.text()?,
        },
        _ => return None,
    };
    (r.at == bytes.len()).then_some(contribution)
}

fn text(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

fn vector(out: &mut Vec<u8>, v: DVec3) {
    for c in v.to_array() {
        out.extend_from_slice(&c.to_le_bytes());
    }
}

fn put_alignment(out: &mut Vec<u8>, a: &Alignment) {
    vector(out, a.translation);
    out.extend_from_slice(&a.heading_rad.to_le_bytes());
    out.extend_from_slice(&(a.observations as u64).to_le_bytes());
    out.extend_from_slice(&(a.rejected as u64).to_le_bytes());
    out.extend_from_slice(&a.position_spread_m.to_le_bytes());
    out.extend_from_slice(&a.heading_spread_deg.to_le_bytes());
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n)?;
        let slice = self.bytes.get(self.at..end)?;
        self.at = end;
        Some(slice)
    }

    fn u8(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }

    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }

    fn f64(&mut self) -> Option<f64> {
        Some(f64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }

    fn vector(&mut self) -> Option<DVec3> {
        Some(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }

    fn text(&mut self) -> Option<String> {
        let n = self.u32()? as usize;
        String::from_utf8(self.take(n)?.to_vec()).ok()
    }

    fn option<T>(&mut self, read: impl FnOnce(&mut Self) -> Option<T>) -> Option<Option<T>> {
        match self.u8()? {
            0 => Some(None),
            1 => read(self).map(Some),
            _ => None,
        }
    }

    fn alignment(&mut self) -> Option<Alignment> {
        Some(Alignment {
            translation: self.vector()?,
            heading_rad: self.f64()?,
            observations: usize::try_from(self.u64()?).ok()?,
            rejected: usize::try_from(self.u64()?).ok()?,
            position_spread_m: self.f64()?,
            heading_spread_deg: self.f64()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn alignment() -> Alignment {
        Alignment {
            translation: DVec3::new(1.0, -2.0, 0.5),
            heading_rad: 0.3,
            observations: 12,
            rejected: 1,
            position_spread_m: 0.004,
            heading_spread_deg: 0.7,
        }
    }

    #[test]
    fn every_kind_of_contribution_comes_back_bitwise() {
        let samples = vec![
            Sample {
                subtrajectory: 0,
                position: DVec3::new(0.1, 1.5, -2.0),
                heading_rad: Some(1.2),
                surface: Some(DVec3::new(0.1, 1.5, 0.001)),
                error_m: 0.12,
            },
            Sample {
                subtrajectory: 3,
                position: DVec3::new(-0.0, f64::MIN_POSITIVE, 7.0),
                heading_rad: None,
                surface: None,
                error_m: 0.0,
            },
        ];
        for c in [
            Contribution::InMap {
                session: "s0000000000000001".into(),
                convention: Convention::Arcore,
                alignment: alignment(),
                samples,
            },
            Contribution::Excluded {
                session: "s0000000000000002".into(),
                alignment: alignment(),
                reason: "it has no results yet — «quoted»".into(),
            },
            Contribution::NotAligned {
                session: "s0000000000000003".into(),
                reason: "no anchors.csv was uploaded".into(),
            },
        ] {
            let bytes = encode(&c);
            assert_eq!(decode(&bytes).as_ref(), Some(&c));
            // Any truncation or a byte more is refused, never a panic.
            for n in 0..bytes.len() {
                assert_eq!(decode(&bytes[..n]), None, "{n}");
            }
            let mut longer = bytes.clone();
            longer.push(0);
            assert_eq!(decode(&longer), None);
        }
        assert_eq!(decode(b"SVC2\x02"), None);
        assert_eq!(decode(b"SVC1\x00\xff\xff\xff\xff"), None);
    }
}
