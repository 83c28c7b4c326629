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

use std::sync::mpsc::{Receiver, Sender, channel, sync_channel};
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

use postgres::{Client, NoTls};

use crate::Error;

/// How long a caller waits for a free connection before its request fails.
pub(super) const CHECKOUT_WAIT: Duration = Duration::from_secs(30);

/// A connection unused this long is checked (an empty query) before use: after a Postgres
/// restart its first query would otherwise fail. A busy connection is never idle this long;
/// one that breaks while busy fails that call (500, the client retries) and is made again.
pub(super) const CHECK_IDLE_AFTER: Duration = Duration::from_secs(1);

/// Work sent to a connection thread.
type Job = Box<dyn FnOnce(&mut Connection) + Send>;

/// One connection, made (again) when needed.
pub(super) struct Connection {
    config: postgres::Config,
    client: Option<Client>,
    last_used: Instant,
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
            let client = self
                .config
                .connect(NoTls)
                .map_err(|e| Error::Database(format!("cannot connect to Postgres: {e}")))?;
            self.client = Some(client);
        }
        self.last_used = Instant::now();
        self.client
            .as_mut()
            .ok_or_else(|| Error::Database("no Postgres connection".into()))
    }
}

/// The connection threads, and the ones free now.
pub(super) struct Pool {
    free: Mutex<Vec<Sender<Job>>>,
    returned: Condvar,
}

impl Pool {
    /// Starts `size` connection threads for `config`; connects one at once, so a wrong URL
    /// or a server that is down is an error at start.
    pub fn open(config: postgres::Config, size: usize) -> Result<Pool, Error> {
        let mut free = Vec::new();
        for n in 0..size.max(1) {
            let (send, receive) = channel::<Job>();
            let mut connection = Connection {
                config: config.clone(),
                client: None,
                last_used: Instant::now(),
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
        };
        pool.lease()?
            .run(|c| Ok(c.simple_query("SELECT 1").map(|_| ())?))?;
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

    /// Runs `f` on a free connection.
    pub fn run<T: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Client) -> Result<T, Error> + Send + 'static,
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
    /// Runs `f` on this lease's connection and waits for its answer.
    pub fn run<T: Send + 'static>(
        &mut self,
        f: impl FnOnce(&mut Client) -> Result<T, Error> + Send + 'static,
    ) -> Result<T, Error> {
        let (answer, receive) = sync_channel(1);
        let job: Job = Box::new(move |connection: &mut Connection| {
            let outcome = connection.client().and_then(f);
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
        self.run(|c| Ok(c.batch_execute("COMMIT")?))
    }
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        if self.open_transaction {
            self.open_transaction = false;
            if let Err(e) = self.run(|c| Ok(c.batch_execute("ROLLBACK")?)) {
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
