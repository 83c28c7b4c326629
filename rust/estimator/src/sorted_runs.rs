//! A growing multiset of non-negative float bits with cursors at the ranks a statistic needs,
//! and the exact sum of the values between two cursors: what one window of the incremental
//! estimate keeps.
//!
//! The values are sorted *runs*, like the levels of a log-structured merge tree, stored back to
//! back in one vector (oldest first, grown by half its length when full, so at most a third of
//! it is spare). Each insertion appends one sorted run, and the two newest runs are merged in
//! place, from the back (only the newer, shorter run is copied aside), while the older one is
//! at most twice as long as the newer, so run lengths more than double from newest to oldest
//! (at most log₂ n + 1 runs) and a value is copied O(log n) times in all (5.6 times on average
//! for 100 trials, each adding one value per earlier trial; 2.3 runs on average).
//!
//! A cursor splits the multiset into the values *below* it (as many as its rank) and the
//! rest, every value below being no larger than any value above; it is one position per
//! run. Inserting a run puts each new value on its side of every cursor (a binary search per
//! cursor); moving a cursor by one value costs one look at each run's value at the cursor.
//! So an insertion of `k` values costs O(k log k) for sorting them, O(k) for the sums and
//! O(steps · runs) for the cursors, where `steps` is how far the wanted ranks moved — at most
//! `k` per cursor — never a pass over the values already stored. Merging two runs moves the
//! cursors' positions by addition.
//!
//! Between two cursors an [`ExactSum`] is kept up to date (every value crossing either cursor
//! is added or removed exactly), so it is the exact sum of the values whose ranks lie
//! between them — a function of the multiset, whatever the order of insertion.

use crate::exact::{ExactSum, add_values};

/// Young runs this long are frozen (4 KB: merging longer runs streams them from memory).
pub(crate) const FREEZE_AT: usize = 512;

/// The most cursors a [`SortedRuns`] has (the mean of inliers needs four).
pub(crate) const MAX_CURSORS: usize = 4;

/// Where a cursor should be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Target {
    /// Exactly this many values below it.
    Rank(usize),
    /// Below it exactly the values (bits) smaller than this.
    Below(u64),
}

/// A cursor's place in one run: how many of the run's values lie below it, and the values
/// on either side (kept here so that finding the next value to cross reads no run data).
#[derive(Debug, Clone, Copy)]
struct Head {
    position: u32,
    /// The run's value at `position` (meaningless when `position` is the run's length).
    above: u64,
    /// The run's value at `position − 1` (meaningless when `position` is 0).
    below: u64,
}

#[derive(Debug, Clone)]
struct Cursor {
    /// Per run, oldest first.
    heads: Vec<Head>,
    /// Values below the cursor (the sum of the positions).
    rank: usize,
    /// For a [`Target::Below`] cursor, its threshold: new values split by it exactly.
    threshold: Option<u64>,
}

/// The sorted runs, the cursors, and the exact sum between two of them.
#[derive(Debug, Clone)]
pub(crate) struct SortedRuns {
    /// The oldest runs, each in its own exact allocation; never moved again.
    frozen: Vec<Box<[u64]>>,
    /// The young runs (after the frozen ones), back to back, oldest first.
    young: Vec<u64>,
    /// Where each young run starts in `young`.
    starts: Vec<u32>,
    /// Length of every run, oldest first.
    lengths: Vec<u32>,
    /// Number of values.
    len: usize,
    /// Length from which the oldest young run is frozen.
    freeze_at: usize,
    cursors: Vec<Cursor>,
    /// The cursors `(lower, upper)` that bound `between`.
    bounds: Option<(usize, usize)>,
    /// Exact sum of the values below cursor `upper` and not below cursor `lower`.
    between: ExactSum,
}

impl SortedRuns {
    /// No values, `cursors` cursors at rank 0, and an exact sum between cursors `bounds`;
    /// young runs of `freeze_at` values or more are frozen.
    pub(crate) fn new(cursors: usize, bounds: Option<(usize, usize)>, freeze_at: usize) -> Self {
        assert!(cursors <= MAX_CURSORS, "at most {MAX_CURSORS} cursors");
        let cursor = Cursor {
            heads: Vec::new(),
            rank: 0,
            threshold: None,
        };
        Self {
            frozen: Vec::new(),
            young: Vec::new(),
            starts: Vec::new(),
            lengths: Vec::new(),
            len: 0,
            freeze_at,
            cursors: vec![cursor; cursors],
            bounds,
            between: ExactSum::new(),
        }
    }

    /// Number of values.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Young run `r`.
    fn young_run(&self, r: usize) -> &[u64] {
        let end = self
            .starts
            .get(r + 1)
            .map_or(self.young.len(), |&e| e as usize);
        &self.young[self.starts[r] as usize..end]
    }

    /// Run `r` (frozen runs first).
    fn run(&self, r: usize) -> &[u64] {
        match self.frozen.get(r) {
            Some(run) => run,
            None => self.young_run(r - self.frozen.len()),
        }
    }

    /// Every run, oldest first.
    #[cfg(test)]
    fn runs(&self) -> impl Iterator<Item = &[u64]> {
        self.frozen
            .iter()
            .map(|r| &r[..])
            .chain((0..self.starts.len()).map(|r| self.young_run(r)))
    }

    /// The head of `cursor` in run `run` at `position`, read from the run.
    fn head(&self, run: usize, position: usize) -> Head {
        let values = self.run(run);
        Head {
            position: position as u32,
            above: values.get(position).copied().unwrap_or(0),
            below: position.checked_sub(1).map_or(0, |p| values[p]),
        }
    }

    /// Values below cursor `cursor`.
    pub(crate) fn rank(&self, cursor: usize) -> usize {
        self.cursors[cursor].rank
    }

    /// The exact sum of the values between the bounding cursors.
    pub(crate) fn between(&self) -> &ExactSum {
        &self.between
    }

    /// The smallest value at or above the cursor (the value of rank `rank(cursor)`) and the
    /// one after it, if there are such values.
    pub(crate) fn above(&self, cursor: usize) -> (Option<u64>, Option<u64>) {
        let heads = &self.cursors[cursor].heads;
        let Some((run, first)) = self.smallest_above(heads) else {
            return (None, None);
        };
        let after_in_run = self.run(run).get(heads[run].position as usize + 1).copied();
        let others = heads
            .iter()
            .zip(&self.lengths)
            .enumerate()
            .filter(|&(r, (h, &len))| r != run && h.position < len)
            .map(|(_, (h, _))| h.above);
        let second = after_in_run.into_iter().chain(others).min();
        (Some(first), second)
    }

    fn smallest_above(&self, heads: &[Head]) -> Option<(usize, u64)> {
        let mut best: Option<(usize, u64)> = None;
        for (r, (h, &len)) in heads.iter().zip(&self.lengths).enumerate() {
            if h.position < len && best.is_none_or(|(_, b)| h.above < b) {
                best = Some((r, h.above));
            }
        }
        best
    }

    fn largest_below(&self, heads: &[Head]) -> Option<(usize, u64)> {
        let mut best: Option<(usize, u64)> = None;
        for (r, h) in heads.iter().enumerate() {
            if h.position > 0 && best.is_none_or(|(_, b)| h.below > b) {
                best = Some((r, h.below));
            }
        }
        best
    }

    /// Adds `sorted` (ascending) as a run. Every cursor keeps its place: a new value goes below
    /// it when smaller than its threshold (or than the smallest value above it); move the
    /// cursors afterwards. `scratch` is a buffer for merging (any content; reused).
    pub(crate) fn insert(&mut self, sorted: &[u64], scratch: &mut Vec<u64>) {
        debug_assert!(sorted.is_sorted());
        if sorted.is_empty() {
            return;
        }
        let mut splits = [0usize; MAX_CURSORS];
        for (c, split) in splits.iter_mut().enumerate().take(self.cursors.len()) {
            let cursor = &self.cursors[c];
            let below = cursor.threshold.unwrap_or_else(|| {
                self.smallest_above(&cursor.heads)
                    .map_or(u64::MAX, |(_, v)| v)
            });
            *split = sorted.partition_point(|&v| v < below);
        }
        if let Some((lower, upper)) = self.bounds {
            // between = below(upper) − below(lower); the new values add to both.
            let (from, to) = (splits[lower], splits[upper]);
            let (range, negative) = if from <= to {
                (from..to, false)
            } else {
                (to..from, true)
            };
            let part = &sorted[range];
            let bound = part.last().copied().unwrap_or(0);
            if negative {
                let mut added = ExactSum::new();
                add_values(&mut added, None, part.iter().copied(), bound);
                self.between.add_sum(&added, true);
            } else {
                add_values(&mut self.between, None, part.iter().copied(), bound);
            }
        }
        self.starts.push(self.young.len() as u32);
        self.young.extend_from_slice(sorted);
        self.lengths.push(sorted.len() as u32);
        self.len += sorted.len();
        let run = self.lengths.len() - 1;
        for (c, &split) in splits.iter().enumerate().take(self.cursors.len()) {
            let head = self.head(run, split);
            let cursor = &mut self.cursors[c];
            cursor.heads.push(head);
            cursor.rank += split;
        }
        while let [.., older, newer] = self.starts[..] {
            let newer_len = self.young.len() - newer as usize;
            if (newer - older) as usize > 2 * newer_len {
                break;
            }
            self.merge_newest(scratch);
        }
        // The oldest young run, once long, is frozen: merging it again would stream it from
        // memory for little gain.
        let first = self.starts.get(1).map_or(self.young.len(), |&s| s as usize);
        if first >= self.freeze_at {
            self.frozen.push(self.young[..first].into());
            self.young.drain(..first);
            self.starts.remove(0);
            self.starts.iter_mut().for_each(|s| *s -= first as u32);
        }
    }

    /// Merges the two newest runs; each cursor's position in the merged run is the sum of its
    /// two positions (the values below it are the smallest ones of both).
    fn merge_newest(&mut self, scratch: &mut Vec<u64>) {
        let newer = self.starts.pop().expect("two runs") as usize;
        let older = *self.starts.last().expect("two runs") as usize;
        scratch.clear();
        scratch.extend_from_slice(&self.young[newer..]);
        // From the back: the largest remaining value of either run goes to the last free slot;
        // the older run's values below every newer one stay where they are.
        let (mut i, mut j, mut k) = (newer, scratch.len(), self.young.len());
        let values = &mut self.young;
        while j > 0 && i > older {
            let (x, y) = (values[i - 1], scratch[j - 1]);
            // Branch-free selection: the comparison of random values is unpredictable.
            let take_older = x > y;
            values[k - 1] = if take_older { x } else { y };
            i -= usize::from(take_older);
            j -= usize::from(!take_older);
            k -= 1;
        }
        values[older..older + j].copy_from_slice(&scratch[..j]);
        let last = self.lengths.pop().expect("two runs");
        *self.lengths.last_mut().expect("two runs") += last;
        let run = self.lengths.len() - 1;
        for c in 0..self.cursors.len() {
            let heads = &mut self.cursors[c].heads;
            let position = heads.pop().expect("a head per run").position
                + heads.last().expect("a head per run").position;
            let head = self.head(run, position as usize);
            *self.cursors[c].heads.last_mut().expect("a head per run") = head;
        }
    }

    /// Moves cursor `cursor` to `target`, one value at a time.
    pub(crate) fn move_to(&mut self, cursor: usize, target: Target) {
        let (up_to, down_to) = match target {
            Target::Rank(rank) => {
                self.cursors[cursor].threshold = None;
                let rank = rank.min(self.len);
                while self.cursors[cursor].rank < rank {
                    let next = self.smallest_above(&self.cursors[cursor].heads);
                    self.step_up(cursor, next.expect("a value above a cursor below the top"));
                }
                while self.cursors[cursor].rank > rank {
                    let next = self.largest_below(&self.cursors[cursor].heads);
                    self.step_down(cursor, next.expect("a value below a cursor above zero"));
                }
                return;
            }
            Target::Below(threshold) => (threshold, threshold),
        };
        self.cursors[cursor].threshold = Some(up_to);
        while let Some(next) = self.smallest_above(&self.cursors[cursor].heads)
            && next.1 < up_to
        {
            self.step_up(cursor, next);
        }
        while let Some(next) = self.largest_below(&self.cursors[cursor].heads)
            && next.1 >= down_to
        {
            self.step_down(cursor, next);
        }
    }

    /// `value`, the smallest above the cursor (in run `run`), goes below it.
    fn step_up(&mut self, cursor: usize, (run, value): (usize, u64)) {
        let position = self.cursors[cursor].heads[run].position as usize + 1;
        let above = self.run(run).get(position).copied().unwrap_or(0);
        let c = &mut self.cursors[cursor];
        c.heads[run] = Head {
            position: position as u32,
            above,
            below: value,
        };
        c.rank += 1;
        self.crossed(cursor, value, true);
    }

    /// `value`, the largest below the cursor (in run `run`), goes above it.
    fn step_down(&mut self, cursor: usize, (run, value): (usize, u64)) {
        let position = self.cursors[cursor].heads[run].position as usize - 1;
        let below = position.checked_sub(1).map_or(0, |p| self.run(run)[p]);
        let c = &mut self.cursors[cursor];
        c.heads[run] = Head {
            position: position as u32,
            above: value,
            below,
        };
        c.rank -= 1;
        self.crossed(cursor, value, false);
    }

    /// Keeps `between` = below(upper) − below(lower) when `value` went below (`down`) or
    /// above cursor `cursor`.
    fn crossed(&mut self, cursor: usize, value: u64, went_below: bool) {
        let Some((lower, upper)) = self.bounds else {
            return;
        };
        let sign = i32::from(cursor == upper) - i32::from(cursor == lower);
        match (sign, went_below) {
            (1, true) | (-1, false) => self.between.add_bits(value),
            (1, false) | (-1, true) => self.between.remove_bits(value),
            _ => {}
        }
    }

    /// Bytes held on the heap (values, positions, run table).
    pub(crate) fn heap_bytes(&self) -> usize {
        self.frozen.iter().map(|r| r.len() * 8).sum::<usize>()
            + self.frozen.capacity() * size_of::<Box<[u64]>>()
            + self.young.capacity() * 8
            + self.starts.capacity() * 4
            + self.lengths.capacity() * 4
            + self
                .cursors
                .iter()
                .map(|c| c.heads.capacity() * size_of::<Head>())
                .sum::<usize>()
            + self.cursors.capacity() * size_of::<Cursor>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Checks every cursor against sorting: its rank, the value at it and after it, and the
    /// sum between the bounds.
    fn check(runs: &SortedRuns, all: &[u64], bounds: (usize, usize)) -> Result<(), TestCaseError> {
        let mut sorted = all.to_vec();
        sorted.sort_unstable();
        prop_assert_eq!(runs.len(), sorted.len());
        for c in 0..runs.cursors.len() {
            let rank = runs.rank(c);
            let (at, next) = runs.above(c);
            prop_assert_eq!(at, sorted.get(rank).copied());
            prop_assert_eq!(next, sorted.get(rank + 1).copied());
        }
        let (low, high) = (runs.rank(bounds.0), runs.rank(bounds.1));
        let mut want = ExactSum::new();
        let (from, to, negative) = if low <= high {
            (low, high, false)
        } else {
            (high, low, true)
        };
        for &v in &sorted[from..to] {
            want.add_bits(v);
        }
        let got = runs.between().value();
        let want = if negative {
            -want.value()
        } else {
            want.value()
        };
        prop_assert_eq!(got, want);
        Ok(())
    }

    proptest! {
        #[test]
        fn cursors_and_sums_equal_sorting(
            batches in prop::collection::vec(prop::collection::vec(0u64..40, 0..30), 1..25),
            targets in prop::collection::vec((0usize..3, 0usize..1000, any::<bool>()), 1..25),
            freeze_at in 2usize..100,
        ) {
            // Small integers as bits: many ties. Three cursors, a sum between 0 and 2.
            let mut runs = SortedRuns::new(3, Some((0, 2)), freeze_at);
            let mut all = Vec::new();
            for (batch, &(cursor, at, by_value)) in batches.iter().zip(targets.iter().cycle()) {
                let mut batch: Vec<u64> = batch.iter().map(|&v| (v as f64 * 0.25).to_bits()).collect();
                batch.sort_unstable();
                runs.insert(&batch, &mut Vec::new());
                all.extend_from_slice(&batch);
                check(&runs, &all, (0, 2))?;
                let target = if by_value {
                    Target::Below((at as f64 * 0.01).to_bits())
                } else {
                    Target::Rank(at % (all.len() + 1))
                };
                runs.move_to(cursor, target);
                if let Target::Below(threshold) = target {
                    prop_assert_eq!(runs.rank(cursor), all.iter().filter(|&&v| v < threshold).count());
                } else if let Target::Rank(rank) = target {
                    prop_assert_eq!(runs.rank(cursor), rank);
                }
                check(&runs, &all, (0, 2))?;
                // Run lengths more than double from newest to oldest.
                let lengths: Vec<usize> = runs.runs().skip(runs.frozen.len()).map(<[u64]>::len).collect();
                prop_assert!(lengths.windows(2).all(|w| w[0] > 2 * w[1]), "{:?}", lengths);
                prop_assert!(runs.runs().all(|r| r.is_sorted()));
            }
        }
    }
}
