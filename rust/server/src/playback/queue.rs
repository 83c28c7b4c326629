//! The playback queue: sim and adb sessions wait here for one of a fixed number of playback
//! workers. Each token's sessions wait in FIFO order; the tokens are served round-robin and
//! each has a limit of sessions playing at once, so one client's hundreds of jobs never
//! starve another's. A waiting session is an id in a list: it holds no thread.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use crate::error::Error;

/// Whose session it is: a token id, or `None` for sessions made without a token.
pub(crate) type Owner = Option<i64>;

/// How a playback job begins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Begin {
    /// The recording was just accepted: `uploaded → playing`.
    Start,
    /// After a restart; the session was already resumed (`Lifecycle::resume`).
    Resume,
}

/// What a client asked of a job while it runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Intent {
    /// Play to the end (or to an adaptive stop).
    Run,
    /// `POST …/cancel`: stop playing, estimate what was played.
    Cancel,
    /// `DELETE`: stop playing and publish nothing; the session is deleted next.
    Delete,
}

/// The handle through which a running job is stopped.
#[derive(Debug, Default)]
pub(crate) struct JobControl {
    /// Set to stop playback (the backends look at it between trials).
    pub cancel: Arc<AtomicBool>,
    intent: AtomicU8,
}

impl JobControl {
    /// Stops playback for `intent` (a delete outranks a cancel).
    pub fn request(&self, intent: Intent) {
        let code = match intent {
            Intent::Run => 0,
            Intent::Cancel => 1,
            Intent::Delete => 2,
        };
        self.intent.fetch_max(code, Ordering::SeqCst);
        if intent != Intent::Run {
            self.cancel.store(true, Ordering::SeqCst);
        }
    }

    pub fn intent(&self) -> Intent {
        match self.intent.load(Ordering::SeqCst) {
            0 => Intent::Run,
            1 => Intent::Cancel,
            _ => Intent::Delete,
        }
    }
}

/// A session handed to a worker.
pub(crate) struct Ticket {
    pub id: String,
    pub begin: Begin,
    pub control: Arc<JobControl>,
}

struct Waiting {
    id: String,
    begin: Begin,
}

/// One token's waiting sessions, oldest first.
struct Lane {
    owner: Owner,
    waiting: VecDeque<Waiting>,
}

#[derive(Default)]
struct State {
    /// Tokens with waiting sessions in round-robin order: the first that may play goes next.
    lanes: VecDeque<Lane>,
    /// Sessions handed to a worker and not finished, with their owner and control.
    active: HashMap<String, (Owner, Arc<JobControl>)>,
    /// Whether the server stops: workers take nothing more.
    closed: bool,
}

impl State {
    fn waiting(&self) -> usize {
        self.lanes.iter().map(|lane| lane.waiting.len()).sum()
    }

    fn playing(&self, owner: Owner) -> usize {
        self.active.values().filter(|(o, _)| *o == owner).count()
    }

    /// The position of the `k`-th waiting session of lane `lane_at`: the sessions the
    /// round-robin serves before it, plus one.
    fn position_of(&self, lane_at: usize, k: usize) -> usize {
        let ahead: usize = self
            .lanes
            .iter()
            .enumerate()
            .map(|(at, lane)| {
                let rounds = if at < lane_at { k + 1 } else { k };
                lane.waiting.len().min(rounds)
            })
            .sum();
        ahead + 1
    }

    fn holds(&self, id: &str) -> bool {
        self.active.contains_key(id)
            || self
                .lanes
                .iter()
                .any(|lane| lane.waiting.iter().any(|w| w.id == id))
    }
}

/// The bounds of the queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct QueueLimits {
    /// Sessions of one owner playing at once (at least 1).
    pub per_owner: usize,
    /// Sessions waiting, all owners together.
    pub max_waiting: usize,
}

/// The playback queue (see the module docs).
pub(crate) struct PlaybackQueue {
    state: Mutex<State>,
    changed: tokio::sync::Notify,
    limits: QueueLimits,
}

impl PlaybackQueue {
    pub fn new(limits: QueueLimits) -> PlaybackQueue {
        PlaybackQueue {
            state: Mutex::new(State::default()),
            changed: tokio::sync::Notify::new(),
            limits: QueueLimits {
                per_owner: limits.per_owner.max(1),
                ..limits
            },
        }
    }

    fn state(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// `Ok` while the queue has room for one more session, else a 503 naming the bound.
    pub fn check_room(&self) -> Result<(), Error> {
        let waiting = self.state().waiting();
        if waiting >= self.limits.max_waiting {
            return Err(Error::Busy(format!(
                "{waiting} sessions wait for playback, the server's limit: try again later"
            )));
        }
        Ok(())
    }

    /// Puts session `id` at the end of its owner's lane (a session already queued or playing
    /// is left as it is).
    pub fn push(&self, owner: Owner, id: &str, begin: Begin) {
        {
            let mut state = self.state();
            if state.holds(id) {
                return;
            }
            let waiting = Waiting {
                id: id.to_string(),
                begin,
            };
            match state.lanes.iter_mut().find(|lane| lane.owner == owner) {
                Some(lane) => lane.waiting.push_back(waiting),
                None => state.lanes.push_back(Lane {
                    owner,
                    waiting: VecDeque::from([waiting]),
                }),
            }
        }
        self.changed.notify_waiters();
    }

    /// Takes session `id` out of the queue; false if it was not waiting.
    pub fn remove(&self, id: &str) -> bool {
        let mut state = self.state();
        for at in 0..state.lanes.len() {
            let lane = &mut state.lanes[at];
            if let Some(k) = lane.waiting.iter().position(|w| w.id == id) {
                lane.waiting.remove(k);
                if lane.waiting.is_empty() {
                    state.lanes.remove(at);
                }
                return true;
            }
        }
        false
    }

    /// The control of session `id`'s job while a worker has it.
    pub fn control(&self, id: &str) -> Option<Arc<JobControl>> {
        self.state()
            .active
            .get(id)
            .map(|(_, control)| control.clone())
    }

    /// Whether session `id` waits or plays.
    pub fn holds(&self, id: &str) -> bool {
        self.state().holds(id)
    }

    /// Where session `id` waits: 1 is next. Counted as the round-robin will serve the lanes
    /// (one session of each token in turn), ignoring the per-token limit.
    pub fn position(&self, id: &str) -> Option<usize> {
        let state = self.state();
        let (lane_at, k) = state.lanes.iter().enumerate().find_map(|(at, lane)| {
            let k = lane.waiting.iter().position(|w| w.id == id)?;
            Some((at, k))
        })?;
        Some(state.position_of(lane_at, k))
    }

    /// Every waiting session with its [`position`](Self::position).
    pub fn positions(&self) -> Vec<(String, usize)> {
        let state = self.state();
        let mut all = Vec::with_capacity(state.waiting());
        for (lane_at, lane) in state.lanes.iter().enumerate() {
            for (k, waiting) in lane.waiting.iter().enumerate() {
                all.push((waiting.id.clone(), state.position_of(lane_at, k)));
            }
        }
        all
    }

    /// The next session a worker may play: the first lane (in round-robin order) whose owner
    /// is below its limit gives its oldest session and moves to the back.
    fn take(&self) -> Option<Ticket> {
        let mut state = self.state();
        let at = (0..state.lanes.len())
            .find(|&at| state.playing(state.lanes[at].owner) < self.limits.per_owner)?;
        let mut lane = state.lanes.remove(at)?;
        let waiting = lane.waiting.pop_front()?;
        let owner = lane.owner;
        if !lane.waiting.is_empty() {
            state.lanes.push_back(lane);
        }
        let control = Arc::new(JobControl::default());
        state
            .active
            .insert(waiting.id.clone(), (owner, control.clone()));
        Some(Ticket {
            id: waiting.id,
            begin: waiting.begin,
            control,
        })
    }

    /// Waits for the next session to play; `None` once the queue is closed.
    pub async fn next(&self) -> Option<Ticket> {
        loop {
            let changed = self.changed.notified();
            tokio::pin!(changed);
            // Registered before looking, so a push between the look and the wait wakes us.
            changed.as_mut().enable();
            if self.state().closed {
                return None;
            }
            if let Some(ticket) = self.take() {
                return Some(ticket);
            }
            changed.await;
        }
    }

    /// A worker is done with session `id`: its owner may play another.
    pub fn finished(&self, id: &str) {
        self.state().active.remove(id);
        self.changed.notify_waiters();
    }

    /// Workers take nothing more (the server stops; waiting sessions resume on next start).
    pub fn close(&self) {
        self.state().closed = true;
        self.changed.notify_waiters();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn queue(per_owner: usize) -> PlaybackQueue {
        PlaybackQueue::new(QueueLimits {
            per_owner,
            max_waiting: 5,
        })
    }

    fn take_ids(q: &PlaybackQueue, n: usize) -> Vec<String> {
        (0..n).filter_map(|_| q.take()).map(|t| t.id).collect()
    }

    #[test]
    fn tokens_are_served_in_turn_each_in_fifo_order() {
        let q = queue(10);
        for id in ["a1", "a2", "a3", "a4"] {
            q.push(Some(1), id, Begin::Start);
        }
        q.push(Some(2), "b1", Begin::Start);
        q.push(Some(2), "b2", Begin::Start);
        q.push(None, "n1", Begin::Resume);
        // Predicted positions match the order they are then served in.
        let predicted: Vec<_> = ["a1", "b1", "n1", "a2", "b2", "a3", "a4"]
            .iter()
            .map(|id| q.position(id).unwrap())
            .collect();
        assert_eq!(predicted, vec![1, 2, 3, 4, 5, 6, 7]);
        // All at once (what a clustered instance publishes), as one by one.
        let mut all = q.positions();
        all.sort_by_key(|p| p.1);
        let order: Vec<_> = all.iter().map(|p| p.0.as_str()).collect();
        assert_eq!(order, ["a1", "b1", "n1", "a2", "b2", "a3", "a4"]);
        assert!(all.iter().all(|(id, at)| q.position(id) == Some(*at)));
        assert_eq!(
            take_ids(&q, 7),
            vec!["a1", "b1", "n1", "a2", "b2", "a3", "a4"]
        );
        assert!(q.take().is_none());
        assert_eq!(q.position("a1"), None);
    }

    #[test]
    fn the_per_token_limit_lets_other_tokens_pass() {
        let q = queue(2);
        for id in ["a1", "a2", "a3"] {
            q.push(Some(1), id, Begin::Start);
        }
        q.push(Some(2), "b1", Begin::Start);
        assert_eq!(take_ids(&q, 2), vec!["a1", "b1"]);
        assert_eq!(take_ids(&q, 1), vec!["a2"]);
        // Token 1 plays two: a3 waits although a worker may be free.
        assert!(q.take().is_none());
        assert!(q.holds("a1") && q.holds("a3"));
        q.finished("a1");
        assert_eq!(take_ids(&q, 1), vec!["a3"]);
        assert!(!q.holds("a1"));
    }

    #[test]
    fn removed_sessions_leave_and_the_bound_is_a_503() {
        let q = queue(1);
        for id in ["a1", "a2", "a3", "a4", "a5"] {
            q.push(Some(1), id, Begin::Start);
        }
        let err = q.check_room().unwrap_err();
        assert_eq!(err.status_and_code().1, "busy", "{err}");
        // A duplicate push changes nothing.
        q.push(Some(1), "a2", Begin::Start);
        assert!(q.remove("a2"));
        assert!(!q.remove("a2"));
        assert!(q.check_room().is_ok());
        assert_eq!(q.position("a3"), Some(2));
        assert_eq!(take_ids(&q, 5), vec!["a1"]);
        assert!(q.control("a1").is_some() && q.control("a3").is_none());
    }

    #[test]
    fn a_delete_outranks_a_cancel_and_both_stop_playback() {
        let control = JobControl::default();
        assert_eq!(control.intent(), Intent::Run);
        control.request(Intent::Delete);
        control.request(Intent::Cancel);
        assert_eq!(control.intent(), Intent::Delete);
        assert!(control.cancel.load(Ordering::SeqCst));
    }

    #[tokio::test]
    async fn a_waiting_worker_wakes_on_push_and_on_close() {
        let q = Arc::new(queue(1));
        let worker = {
            let q = q.clone();
            tokio::spawn(async move { q.next().await.map(|t| t.id) })
        };
        tokio::task::yield_now().await;
        q.push(None, "x", Begin::Start);
        let got = tokio::time::timeout(std::time::Duration::from_secs(5), worker)
            .await
            .unwrap()
            .unwrap();
        assert_eq!(got.as_deref(), Some("x"));
        let idle = {
            let q = q.clone();
            tokio::spawn(async move { q.next().await.is_none() })
        };
        tokio::task::yield_now().await;
        q.close();
        assert!(
            tokio::time::timeout(std::time::Duration::from_secs(5), idle)
                .await
                .unwrap()
                .unwrap()
        );
    }
}
