//! A fixed set of Postgres connections, each owned by its own OS thread.
//!
//! Why threads: the metadata traits are synchronous and are called straight from async
//! handlers (as SQLite's are). `postgres::Client` blocks on a runtime of its own and panics
//! when called on a thread that is driving a tokio runtime, so no handler thread ever touches
//! a client: a call sends a closure to a connection thread (made outside any runtime) and
//! waits for its answer — inside `block_in_place` on a multi-threaded runtime, so the other
//! tasks of that worker move elsewhere meanwhile. A [`Lease`] holds one connection for
//! several calls (a transaction that spans a caller's callback); it rolls back what it left
//! open when dropped.
//!
//! Bounds: `size` connections (and threads); a caller waits at most [`CHECKOUT_WAIT`] for
//! one. A connection that broke (Postgres restarted) is made again on its next use; one idle
//! for more than [`CHECK_IDLE_AFTER`] is checked with an empty query first.
//!
//! A restart or failover of Postgres is ridden out, not passed on: making a connection is
//! tried again for up to [`RECONNECT_WAIT`] while the server cannot be reached or says it
//! is starting or stopping (a wrong password or database fails at once), and a call outside
//! a transaction whose connection broke under it runs once more on a new one. A call inside
//! a transaction, and its `COMMIT`, are never run again: the transaction is lost with the
//! connection, and the caller gets the error.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel, sync_channel};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use postgres::Client;
use tokio_postgres_rustls::MakeRustlsConnect;

use crate::error::Error;

/// How long a caller waits for a free connection before its request fails.
pub(super) const CHECKOUT_WAIT: Duration = Duration::from_secs(30);

/// A connection unused this long is checked (an empty query) before use: after a Postgres
/// restart its first query would otherwise fail. A busy connection is never idle this long;
/// one that breaks while busy fails that call (500, the client retries) and is made again.
pub(super) const CHECK_IDLE_AFTER: Duration = Duration::from_secs(1);

/// How long making a connection is tried again while Postgres cannot be reached (restarting,
/// failing over); a caller waits this long at most on top of [`CHECKOUT_WAIT`].
pub(super) const RECONNECT_WAIT: Duration = Duration::from_secs(20);

/// What a call in a transaction whose connection broke answers.
const TRANSACTION_LOST: &str =
    "the connection to Postgres broke during a transaction, which is rolled back";

/// The longest pause between two connection attempts.
const RECONNECT_PAUSE: Duration = Duration::from_secs(1);

/// Work sent to a connection thread.
type Job = Box<dyn FnOnce(&mut Connection) + Send>;

/// One connection, made (again) when needed.
pub(super) struct Connection {
    config: postgres::Config,
    tls: MakeRustlsConnect,
    client: Option<Client>,
    last_used: Instant,
    /// Whether connecting is tried again for [`RECONNECT_WAIT`] (not while the pool opens:
    /// a server that is down at start is named at once).
    patient: Arc<AtomicBool>,
}

impl Connection {
    /// The client, connecting first when there is none or it broke.
    fn client(&mut self) -> Result<&mut Client, Error> {
        let stale = self.last_used.elapsed() > CHECK_IDLE_AFTER;
        let broken = match &mut self.client {
            None => true,
            Some(c) => c.is_closed() || (stale && c.is_valid(Duration::from_secs(2)).is_err()),
        };
        if broken {
            self.client = None;
            self.client = Some(self.connect()?);
        }
        self.last_used = Instant::now();
        self.client
            .as_mut()
            .ok_or_else(|| Error::Database("no Postgres connection".into()))
    }

    /// The connection an open transaction is on; an error if it broke (the transaction is
    /// lost: a new connection would run the rest of it alone).
    fn transaction_client(&mut self) -> Result<&mut Client, Error> {
        self.last_used = Instant::now();
        match &mut self.client {
            Some(c) if !c.is_closed() => Ok(c),
            _ => Err(Error::Database(TRANSACTION_LOST.into())),
        }
    }

    /// A new connection, tried again while Postgres cannot be reached (see the module docs).
    fn connect(&self) -> Result<Client, Error> {
        let deadline = Instant::now() + RECONNECT_WAIT;
        let mut pause = Duration::from_millis(50);
        let mut said = false;
        loop {
            let e = match self.config.connect(self.tls.clone()) {
                Ok(client) => {
                    if said {
                        log::info!("database: connected to Postgres again");
                    }
                    return Ok(client);
                }
                Err(e) => e,
            };
            let patient = self.patient.load(Ordering::Relaxed);
            if !patient || !unreachable(&e) || Instant::now() + pause > deadline {
                return Err(Error::Database(format!(
                    "cannot connect to Postgres: {}",
                    with_causes(&e)
                )));
            }
            if !said {
                log::warn!(
                    "database: cannot connect to Postgres ({}); trying again for up to {} s",
                    with_causes(&e),
                    RECONNECT_WAIT.as_secs()
                );
                said = true;
            }
            std::thread::sleep(pause);
            pause = (pause * 2).min(RECONNECT_PAUSE);
        }
    }

    /// Whether the connection broke (rather than the call failing on a sound one): it is
    /// closed, or does not answer an empty query. Checked only after a call failed.
    fn broke(&mut self) -> bool {
        match &mut self.client {
            None => true,
            Some(c) => c.is_closed() || c.is_valid(Duration::from_secs(2)).is_err(),
        }
    }
}

/// An error and its causes (a TLS handshake's says which certificate check failed).
fn with_causes(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}

/// Whether a failed connection attempt may succeed later: no answer (refused, reset, timed
/// out), or Postgres saying it is starting or shutting down. A refusal of the user, password
/// or database is not.
fn unreachable(e: &postgres::Error) -> bool {
    use postgres::error::SqlState;
    match e.code() {
        None => true,
        Some(code) => [
            SqlState::CANNOT_CONNECT_NOW,
            SqlState::ADMIN_SHUTDOWN,
            SqlState::CRASH_SHUTDOWN,
            SqlState::TOO_MANY_CONNECTIONS,
        ]
        .contains(code),
    }
}

/// The connection threads, and the ones free now.
pub(super) struct Pool {
    free: Mutex<Vec<Sender<Job>>>,
    returned: Condvar,
    patient: Arc<AtomicBool>,
}

impl Pool {
    /// Starts `size` connection threads for `config`; connects one at once, so a wrong URL
    /// or a server that is down is an error at start.
    pub fn open(
        config: postgres::Config,
        tls: MakeRustlsConnect,
        size: usize,
    ) -> Result<Pool, Error> {
        let mut free = Vec::new();
        let patient = Arc::new(AtomicBool::new(false));
        for n in 0..size.max(1) {
            let (send, receive) = channel::<Job>();
            let mut connection = Connection {
                config: config.clone(),
                tls: tls.clone(),
                client: None,
                last_used: Instant::now(),
                patient: patient.clone(),
            };
            std::thread::Builder::new()
                .name(format!("sitar-pg-{n}"))
                .spawn(move || serve(&mut connection, receive))
                .map_err(|e| Error::Internal(format!("cannot start a Postgres thread: {e}")))?;
            free.push(send);
        }
        let pool = Pool {
            free: Mutex::new(free),
            returned: Condvar::new(),
            patient,
        };
        pool.lease()?
            .run(|c| Ok(c.simple_query("SELECT 1").map(|_| ())?))?;
        // Reached once: from now on an unreachable server is waited for.
        pool.patient.store(true, Ordering::Relaxed);
        Ok(pool)
    }

    /// One connection for this caller alone until the lease is dropped.
    pub fn lease(&self) -> Result<Lease<'_>, Error> {
        let deadline = Instant::now() + CHECKOUT_WAIT;
        let mut free = self.free.lock().unwrap_or_else(|p| p.into_inner());
        loop {
            if let Some(sender) = free.pop() {
                return Ok(Lease {
                    pool: self,
                    sender: Some(sender),
                    open_transaction: false,
                });
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(Error::Database(format!(
                    "every Postgres connection was busy for {} s",
                    CHECKOUT_WAIT.as_secs()
                )));
            }
            free = self
                .returned
                .wait_timeout(free, deadline - now)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
    }

    /// Runs `f` on a free connection (once more on a new one if the connection broke).
    pub fn run<T: Send + 'static>(
        &self,
        f: impl FnMut(&mut Client) -> Result<T, Error> + Send + 'static,
    ) -> Result<T, Error> {
        self.lease()?.run(f)
    }
}

/// A connection thread: runs what it is sent until the pool is dropped. A call that panics
/// (a column of an unexpected type) fails alone: its caller gets an error, the connection is
/// made again, and the thread goes on serving.
fn serve(connection: &mut Connection, jobs: Receiver<Job>) {
    while let Ok(job) = jobs.recv() {
        let ran = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job(connection)));
        if ran.is_err() {
            log::error!("a Postgres call panicked; its connection is made again");
            connection.client = None;
        }
    }
}

/// One connection held by one caller.
pub(super) struct Lease<'p> {
    pool: &'p Pool,
    sender: Option<Sender<Job>>,
    open_transaction: bool,
}

impl Lease<'_> {
    /// Runs `f` on this lease's connection and waits for its answer. Outside a transaction
    /// a call whose connection broke runs once more on a new one.
    pub fn run<T: Send + 'static>(
        &mut self,
        f: impl FnMut(&mut Client) -> Result<T, Error> + Send + 'static,
    ) -> Result<T, Error> {
        let in_transaction = self.open_transaction;
        self.send(f, in_transaction)
    }

    /// Runs `f` on the connection: alone, once more on a new connection if it broke; in a
    /// transaction, on the transaction's connection or not at all.
    fn send<T: Send + 'static>(
        &mut self,
        mut f: impl FnMut(&mut Client) -> Result<T, Error> + Send + 'static,
        in_transaction: bool,
    ) -> Result<T, Error> {
        let (answer, receive) = sync_channel(1);
        let job: Job = Box::new(move |connection: &mut Connection| {
            if in_transaction {
                let outcome = match connection.transaction_client().and_then(&mut f) {
                    Err(e) if connection.client.as_ref().is_none_or(|c| c.is_closed()) => {
                        Err(Error::Database(format!("{TRANSACTION_LOST} ({e})")))
                    }
                    outcome => outcome,
                };
                let _ = answer.send(outcome);
                return;
            }
            let mut outcome = match connection.client() {
                Ok(client) => f(client),
                // Making the connection was tried again already: nothing ran to run again.
                Err(e) => {
                    let _ = answer.send(Err(e));
                    return;
                }
            };
            if let Err(e) = &outcome
                && connection.broke()
            {
                log::warn!("database: the connection broke ({e}); the call runs again");
                connection.client = None;
                outcome = connection.client().and_then(&mut f);
            }
            let _ = answer.send(outcome);
        });
        let sender = self
            .sender
            .as_ref()
            .ok_or_else(|| Error::Internal("Postgres lease used after release".into()))?;
        sender
            .send(job)
            .map_err(|_| Error::Database("a Postgres connection thread ended".into()))?;
        wait(receive)
    }

    /// Starts a transaction that later calls on this lease continue; [`Lease::commit`] ends
    /// it, and dropping the lease first rolls it back.
    pub fn begin(&mut self) -> Result<(), Error> {
        self.run(|c| Ok(c.batch_execute("BEGIN")?))?;
        self.open_transaction = true;
        Ok(())
    }

    /// Commits the transaction [`Lease::begin`] started.
    pub fn commit(&mut self) -> Result<(), Error> {
        self.open_transaction = false;
        // Never on a new connection: there it would commit nothing and say so.
        self.send(|c| Ok(c.batch_execute("COMMIT")?), true)
    }
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        if self.open_transaction {
            self.open_transaction = false;
            if let Err(e) = self.send(|c| Ok(c.batch_execute("ROLLBACK")?), true) {
                log::warn!("Postgres: rollback failed: {e}");
            }
        }
        if let Some(sender) = self.sender.take() {
            let mut free = self.pool.free.lock().unwrap_or_else(|p| p.into_inner());
            free.push(sender);
            self.pool.returned.notify_one();
        }
    }
}

/// Waits for a connection thread's answer.
fn wait<T>(receive: Receiver<Result<T, Error>>) -> Result<T, Error> {
    crate::storage::blocking::wait(receive).unwrap_or_else(|| {
        Err(Error::Database(
            "a Postgres call ended without an answer (logged)".into(),
        ))
    })
}

/// A Postgres failure is the store's own: a 500 `database` that names no backend type.
impl From<postgres::Error> for Error {
    fn from(e: postgres::Error) -> Error {
        // The server's message (and its detail) says what is wrong; `Display` alone may only
        // say "db error".
        match e.as_db_error() {
            Some(db) => Error::Database(format!("{}: {}", db.severity(), db.message())),
            None => Error::Database(e.to_string()),
        }
    }
}
