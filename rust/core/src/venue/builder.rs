//! Cells from contributions: the whole map at once ([`build_map`]) or kept up to date as
//! sessions join and leave ([`MapBuilder`]).

use std::collections::{BTreeMap, HashSet};

use glam::DVec3;

use super::trim_mean::{CELL_TRIM, trim_mean};
use super::{CellKind, Contribution, VenueCell, VenueMap, VenueSession};
use crate::{Convention, Thresholds};

/// What a venue is, as far as its map is concerned.
#[derive(Debug, Clone, PartialEq)]
pub struct VenueSpec {
    /// The venue id (`v` and 16 hex digits).
    pub id: String,
    /// Its name.
    pub name: String,
    /// The anchor id its sessions observe.
    pub anchor: String,
    /// Cell edge (m): finite and > 0 (the backend keeps it within 0.05…2); another value
    /// gives meaningless cells, never a panic.
    pub cell_m: f64,
    /// The convention of the map's coordinates (its sessions').
    pub convention: Convention,
}

/// The map of `contributions` (listed in the given order; a session id given twice counts
/// once, the later one winning) with the cells seen by at least `min_sessions` sessions.
pub fn build_map(spec: &VenueSpec, contributions: &[Contribution], min_sessions: u32) -> VenueMap {
    MapBuilder::with_contributions(spec.clone(), contributions).map(min_sessions)
}

/// Calls `put` with the cell and the member of each of a contribution's samples (its path
/// cell, then its surface cell), mirrored into the venue's convention when the session's
/// differs.
fn placements(
    contribution: &Contribution,
    spec: &VenueSpec,
    slot: u64,
    mut put: impl FnMut(CellKey, Member),
) {
    let mirror = matches!(contribution, Contribution::InMap { convention, .. }
        if *convention != spec.convention);
    let to_venue = |p: DVec3| {
        if mirror {
            DVec3::new(p.x, p.y, -p.z)
        } else {
            p
        }
    };
    for s in contribution.samples() {
        let member = Member {
            slot,
            error_m: s.error_m,
            sector: s.sector(),
        };
        put(
            cell_key(CellKind::Path, to_venue(s.position), spec.cell_m),
            member,
        );
        if let Some(surface) = s.surface {
            put(
                cell_key(CellKind::Surface, to_venue(surface), spec.cell_m),
                member,
            );
        }
    }
}

/// A cell's place: kind (0 path, 1 surface), then the integer index per axis. Its order is
/// the map's order of cells.
type CellKey = (u8, [i64; 3]);

/// The index of the cell holding `p`: [`cell_index`] per axis.
fn cell_key(kind: CellKind, p: DVec3, cell_m: f64) -> CellKey {
    let index = |v: f64| cell_index(v, cell_m);
    (kind as u8, [index(p.x), index(p.y), index(p.z)])
}

/// The index along one axis of the cell holding venue coordinate `v`: `floor(v / cell_m +
/// ½)`, the nearest multiple of `cell_m`. Cells are centred on multiples of `cell_m` (cell
/// `i` spans `[(i − ½)·cell_m, (i + ½)·cell_m)`, centre `i·cell_m`), so the anchor's own
/// plane (a venue coordinate of 0) and planes at whole multiples of `cell_m` — walls at whole
/// metres for the usual cell sizes — lie in the middle of a cell, never on a boundary where
/// millimetres of alignment would split one wall between two rows of cells.
pub fn cell_index(v: f64, cell_m: f64) -> i64 {
    (v / cell_m + 0.5).floor() as i64
}

/// The centre along one axis of cell `i` ([`cell_index`]): `i·cell_m`.
pub fn cell_centre(i: i64, cell_m: f64) -> f64 {
    i as f64 * cell_m
}

/// One sub-trajectory in one cell.
#[derive(Debug, Clone, Copy)]
struct Member {
    /// The session's slot (unique per [`MapBuilder::add`]).
    slot: u64,
    error_m: f64,
    sector: Option<u8>,
}

#[derive(Debug, Default)]
struct CellState {
    /// In the order added; one session's members are consecutive (added in one call).
    members: Vec<Member>,
    /// The cell as last computed; `None` once members change.
    cached: Option<VenueCell>,
}

#[derive(Debug)]
struct Entry {
    /// How the session is listed in the map.
    listing: VenueSession,
    slot: u64,
    /// The cells it has members in (sorted, distinct).
    cells: Vec<CellKey>,
}

/// A venue map kept up to date as sessions join and leave: per-cell members, each cell
/// recomputed only when its members changed. Adding a session costs its own samples (plus
/// the cells it touches); [`MapBuilder::map`] recomputes the changed cells and copies the rest.
#[derive(Debug)]
pub struct MapBuilder {
    spec: VenueSpec,
    entries: Vec<Entry>,
    cells: BTreeMap<CellKey, CellState>,
    next_slot: u64,
}

impl MapBuilder {
    /// An empty map of the venue `spec`.
    pub fn new(spec: VenueSpec) -> Self {
        Self {
            spec,
            entries: Vec::new(),
            cells: BTreeMap::new(),
            next_slot: 0,
        }
    }

    /// The map of `contributions` at once (as adding each in turn, but one sort instead of
    /// a tree insertion per sample).
    pub fn with_contributions(spec: VenueSpec, contributions: &[Contribution]) -> Self {
        let mut builder = Self::new(spec);
        let mut ids = HashSet::new();
        if !contributions.iter().all(|c| ids.insert(c.session())) {
            // A session given twice: the later replaces the earlier, as `add` does.
            for c in contributions {
                builder.add(c);
            }
            return builder;
        }
        let total: usize = contributions.iter().map(|c| 2 * c.samples().len()).sum();
        let mut placed: Vec<(CellKey, Member)> = Vec::with_capacity(total);
        for c in contributions {
            let slot = builder.next_slot;
            builder.next_slot += 1;
            let first = placed.len();
            placements(c, &builder.spec, slot, |key, member| {
                placed.push((key, member))
            });
            let mut cells: Vec<CellKey> = placed[first..].iter().map(|(k, _)| *k).collect();
            cells.sort_unstable();
            cells.dedup();
            builder.entries.push(Entry {
                listing: listing(c),
                slot,
                cells,
            });
        }
        // Grouped by cell, each session's members consecutive (as `add` leaves them).
        placed.sort_unstable_by_key(|(key, m)| (*key, m.slot));
        builder.cells = placed
            .chunk_by(|a, b| a.0 == b.0)
            .map(|chunk| {
                let state = CellState {
                    members: chunk.iter().map(|(_, m)| *m).collect(),
                    cached: None,
                };
                (chunk[0].0, state)
            })
            .collect();
        builder
    }

    /// The venue.
    pub fn spec(&self) -> &VenueSpec {
        &self.spec
    }

    /// Sessions in the map, in the order added.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no session was added.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Adds a session's contribution (replacing an earlier one of the same session, which
    /// keeps its place in the list). Samples given in another convention than the venue's
    /// are mirrored into it (`z → −z`, the same physical place).
    pub fn add(&mut self, contribution: &Contribution) {
        let position = self.detach(contribution.session());
        let slot = self.next_slot;
        self.next_slot += 1;
        let mut touched = Vec::new();
        let cells = &mut self.cells;
        placements(contribution, &self.spec, slot, |key, member| {
            let cell = cells.entry(key).or_default();
            cell.members.push(member);
            cell.cached = None;
            touched.push(key);
        });
        touched.sort_unstable();
        touched.dedup();
        let entry = Entry {
            listing: listing(contribution),
            slot,
            cells: touched,
        };
        match position {
            Some(i) => self.entries.insert(i, entry),
            None => self.entries.push(entry),
        }
    }

    /// Removes a session; `false` when it was not in the map.
    pub fn remove(&mut self, session: &str) -> bool {
        self.detach(session).is_some()
    }

    /// Takes a session's members out of its cells; returns where it was listed.
    fn detach(&mut self, session: &str) -> Option<usize> {
        let i = self
            .entries
            .iter()
            .position(|e| listed_id(&e.listing) == session)?;
        let entry = self.entries.remove(i);
        for key in &entry.cells {
            if let Some(cell) = self.cells.get_mut(key) {
                cell.members.retain(|m| m.slot != entry.slot);
                cell.cached = None;
                if cell.members.is_empty() {
                    self.cells.remove(key);
                }
            }
        }
        Some(i)
    }

    /// The map now, with the cells seen by at least `min_sessions` sessions (cells sorted by
    /// kind, path first, then by index along x, y, z).
    pub fn map(&mut self, min_sessions: u32) -> VenueMap {
        let cell_m = self.spec.cell_m;
        let mut errors = Vec::new();
        let mut cells = Vec::with_capacity(self.cells.len());
        for (key, state) in &mut self.cells {
            let cell = state
                .cached
                .get_or_insert_with(|| compute_cell(*key, &state.members, cell_m, &mut errors));
            if cell.sessions >= min_sessions {
                cells.push(cell.clone());
            }
        }
        VenueMap {
            id: self.spec.id.clone(),
            name: self.spec.name.clone(),
            anchor: self.spec.anchor.clone(),
            cell_m,
            convention: self.spec.convention,
            unit: "m".into(),
            sessions: self.entries.iter().map(|e| e.listing.clone()).collect(),
            cells,
        }
    }
}

/// A cell from its members: centre, distinct sessions, trimmed-mean error and class,
/// direction counts.
fn compute_cell(key: CellKey, members: &[Member], cell_m: f64, errors: &mut Vec<f64>) -> VenueCell {
    let (kind, index) = key;
    let centre = |i: i64| cell_centre(i, cell_m);
    let mut directions = [0u32; 8];
    let mut sessions = 0u32;
    let mut last_slot = None;
    errors.clear();
    for m in members {
        if last_slot != Some(m.slot) {
            sessions += 1;
            last_slot = Some(m.slot);
        }
        errors.push(m.error_m);
        if let Some(s) = m.sector {
            directions[usize::from(s)] += 1;
        }
    }
    let error_m = trim_mean(errors, CELL_TRIM);
    VenueCell {
        center: [centre(index[0]), centre(index[1]), centre(index[2])],
        kind: if kind == 0 {
            CellKind::Path
        } else {
            CellKind::Surface
        },
        sessions,
        subtrajectories: members.len() as u32,
        error_m,
        class: Thresholds::DEFAULT_M.classify(error_m),
        directions,
    }
}

/// The session id of a listing.
fn listed_id(listing: &VenueSession) -> &str {
    match listing {
        VenueSession::Aligned { id, .. } | VenueSession::NotAligned { id, .. } => id,
    }
}

/// How a contribution is listed in the map: aligned with its spread and the number of
/// sub-trajectories it brought, or not in the map with the reason.
fn listing(c: &Contribution) -> VenueSession {
    match c {
        Contribution::InMap {
            session,
            alignment,
            samples,
            ..
        } => VenueSession::Aligned {
            id: session.clone(),
            aligned: true,
            observations: alignment.observations as u32,
            position_spread_m: alignment.position_spread_m,
            heading_spread_deg: alignment.heading_spread_deg,
            subtrajectories: samples.len() as u32,
        },
        Contribution::Excluded {
            session, reason, ..
        }
        | Contribution::NotAligned { session, reason } => VenueSession::NotAligned {
            id: session.clone(),
            aligned: false,
            reason: reason.clone(),
        },
    }
}
