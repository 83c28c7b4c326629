//! The cluster metadata store: Postgres, for several `sitar serve` instances on one database
//! (`sitar serve --database postgres://…`). Same tables and guarantees as the embedded
//! SQLite store ([`crate::storage::sqlite`]), one file per concern; the schema is versioned
//! ([`migrations`], applied at start). Calls run on a fixed set of connection threads
//! ([`pool`]: why threads, and the bounds).
//!
//! Connection settings: the URL first, then the usual `PG*` variables for what it leaves out
//! (`PGHOST`, `PGPORT`, `PGUSER`, `PGPASSWORD`, `PGDATABASE`, `PGAPPNAME`,
//! `PGCONNECT_TIMEOUT`). Connections are plain TCP or a Unix socket (no TLS): keep the
//! database on a private network or the same host.

use std::str::FromStr;

use tokio_postgres_rustls::MakeRustlsConnect;

use crate::error::Error;

pub(crate) mod copy;
mod deletes;
mod hosts;
mod instances;
mod jobs;
mod joining;
mod leases;
mod migrations;
mod pool;
mod sessions;
pub(crate) mod tls;
mod tokens;
mod trials;
mod usage;
mod venues;

/// Connections (and threads) per instance.
pub(crate) const CONNECTIONS: usize = 8;

/// The cluster metadata store.
pub(crate) struct PgStore {
    pool: pool::Pool,
}

/// Whether `url` names a Postgres database (`postgres://` or `postgresql://`).
pub(crate) fn is_postgres_url(url: &str) -> bool {
    url.starts_with("postgres://") || url.starts_with("postgresql://")
}

/// The connection settings of `url`, with the `PG*` variables for what it leaves out, and
/// the TLS connector its `sslmode` asks for (see [`tls`]).
pub(crate) fn connection(url: &str) -> Result<(postgres::Config, MakeRustlsConnect), Error> {
    let (_, settings) = tls::take_settings(url)?;
    Ok((config(url)?, tls::connector(&settings)?))
}

/// The connection settings of `url`, with the `PG*` variables for what it leaves out (its
/// `sslmode` as rust-postgres knows it: disable, prefer or require).
pub(crate) fn config(url: &str) -> Result<postgres::Config, Error> {
    let (plain, settings) = tls::take_settings(url)?;
    let mut config = postgres::Config::from_str(&plain)
        .map_err(|e| Error::Config(format!("--database {}: {e}", redact(url))))?;
    config.ssl_mode(match settings {
        tls::TlsSettings {
            check: tls::Check::Disable,
            ..
        } => postgres::config::SslMode::Disable,
        tls::TlsSettings { required: true, .. } => postgres::config::SslMode::Require,
        _ => postgres::config::SslMode::Prefer,
    });
    let var = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
    if config.get_hosts().is_empty()
        && let Some(host) = var("PGHOST")
    {
        if host.starts_with('/') {
            config.host_path(host);
        } else {
            config.host(&host);
        }
    }
    if config.get_hosts().is_empty() {
        config.host("localhost");
    }
    if config.get_ports().is_empty()
        && let Some(port) = var("PGPORT")
    {
        let port: u16 = port
            .parse()
            .map_err(|_| Error::Config(format!("PGPORT: {port:?} is not a port number")))?;
        config.port(port);
    }
    if config.get_user().is_none() {
        let user = var("PGUSER")
            .or_else(|| var("USER"))
            .unwrap_or_else(|| "postgres".into());
        config.user(&user);
    }
    if config.get_password().is_none()
        && let Some(password) = var("PGPASSWORD")
    {
        config.password(password);
    }
    if config.get_dbname().is_none()
        && let Some(db) = var("PGDATABASE")
    {
        config.dbname(&db);
    }
    if config.get_application_name().is_none() {
        config.application_name(&var("PGAPPNAME").unwrap_or_else(|| "sitar".into()));
    }
    if config.get_connect_timeout().is_none() {
        let secs = var("PGCONNECT_TIMEOUT")
            .and_then(|s| s.parse().ok())
            .unwrap_or(10);
        config.connect_timeout(std::time::Duration::from_secs(secs));
    }
    Ok(config)
}

/// `url` without its password, for messages.
pub(crate) fn redact(url: &str) -> String {
    match (url.find("://"), url.rfind('@')) {
        (Some(scheme), Some(at)) if at > scheme => {
            let credentials = &url[scheme + 3..at];
            match credentials.find(':') {
                Some(colon) => format!(
                    "{}{}:***{}",
                    &url[..scheme + 3],
                    &credentials[..colon],
                    &url[at..]
                ),
                None => url.to_string(),
            }
        }
        _ => url.to_string(),
    }
}

impl PgStore {
    /// Connects to `url` and applies the migrations the database lacks.
    pub fn open(url: &str) -> Result<PgStore, Error> {
        let (config, tls) = connection(url)?;
        let pool = pool::Pool::open(config, tls, CONNECTIONS).map_err(|e| match e {
            Error::Database(why) => Error::Database(format!("{}: {why}", redact(url))),
            other => other,
        })?;
        pool.run(|c| migrations::migrate(c).map(|_| ()))?;
        Ok(PgStore { pool })
    }
}

/// A column that must fit a `u32`; an error naming the column otherwise.
pub(super) fn u32_column(row: &postgres::Row, index: usize, column: &str) -> Result<u32, String> {
    let value: i64 = row.try_get(index).map_err(|e| format!("{column}: {e}"))?;
    u32::try_from(value).map_err(|_| format!("{column}: {value} is out of range"))
}

#[cfg(test)]
pub(crate) mod test_database;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cluster_store_passes_the_conformance_suite() {
        let Some(url) = test_database::fresh("conformance") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        crate::storage::conformance::metadata_store(&store);
        // What it stored is there for another instance on the same database.
        drop(store);
        let again = PgStore::open(&url).unwrap();
        use crate::storage::SessionStore;
        assert!(again.session("s1000000000000005").unwrap().is_some());
    }

    #[test]
    fn the_cluster_worker_store_passes_the_conformance_suite() {
        let Some(url) = test_database::fresh("workers") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        crate::storage::worker_conformance::worker_store(&store);
        crate::storage::worker_conformance::only_the_player_takes(&store);
        // Two instances on one database (each its own connections) racing.
        let Some(url) = test_database::fresh("workers_racing") else {
            return;
        };
        let (a, b) = (PgStore::open(&url).unwrap(), PgStore::open(&url).unwrap());
        crate::storage::worker_conformance::racing_instances(&a, &b);
    }

    #[test]
    fn unfinished_deletes_are_claimed_once_across_instances() {
        let Some(url) = test_database::fresh("unfinished_deletes") else {
            return;
        };
        let (a, b) = (PgStore::open(&url).unwrap(), PgStore::open(&url).unwrap());
        crate::storage::delete_conformance::unfinished_deletes(&a);
        crate::storage::delete_conformance::racing_sweepers(&a, &b);
    }

    #[test]
    fn migrations_run_once_and_a_newer_schema_is_refused() {
        let Some(url) = test_database::fresh("migrations") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        let versions = store
            .pool
            .run(|c| {
                Ok(c.query(
                    "SELECT version FROM schema_migrations ORDER BY version",
                    &[],
                )?
                .iter()
                .map(|r| r.get::<_, i64>(0))
                .collect::<Vec<_>>())
            })
            .unwrap();
        assert_eq!(versions, migrations::versions());
        // Two more instances on the same database apply nothing again.
        std::thread::scope(|s| {
            let a = s.spawn(|| PgStore::open(&url).map(|_| ()));
            let b = s.spawn(|| PgStore::open(&url).map(|_| ()));
            a.join().unwrap().unwrap();
            b.join().unwrap().unwrap();
        });
        store
            .pool
            .run(|c| {
                c.execute(
                    "INSERT INTO schema_migrations VALUES (999, 'future', 0)",
                    &[],
                )?;
                Ok(())
            })
            .unwrap();
        let err = PgStore::open(&url).err().unwrap().to_string();
        assert!(err.contains("version 999"), "{err}");
    }

    #[test]
    fn a_database_that_is_down_is_named_without_its_password() {
        // A port nothing listens on (the test database's own port + 1 is not promised to be
        // free; port 9 of loopback is "discard", closed on these machines).
        let err = PgStore::open("postgres://sitar:secret@127.0.0.1:9/sitar")
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("sitar:***@127.0.0.1:9"), "{err}");
        assert!(!err.contains("secret"), "{err}");
        let bad = PgStore::open("postgres://[::1").err().unwrap().to_string();
        assert!(bad.contains("--database"), "{bad}");
    }

    #[test]
    fn connections_the_server_dropped_are_made_again() {
        let Some(url) = test_database::fresh("reconnect") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        use crate::storage::TokenStore;
        store
            .insert_token(
                "before",
                crate::model::Role::App,
                "sitar_reconnectAAAAAAAAAAAAAAAAAAAA",
            )
            .unwrap();
        // What a Postgres restart does to every connection: the server ends them.
        let mut admin = config(&url).unwrap().connect(postgres::NoTls).unwrap();
        let dropped = admin
            .execute(
                "SELECT pg_terminate_backend(pid) FROM pg_stat_activity \
                 WHERE datname = current_database() AND pid <> pg_backend_pid()",
                &[],
            )
            .unwrap();
        assert!(dropped >= 1, "{dropped}");
        std::thread::sleep(pool::CHECK_IDLE_AFTER + std::time::Duration::from_millis(200));
        // Every connection of the pool answers again (more calls than connections).
        for _ in 0..2 * CONNECTIONS {
            assert!(store.has_token("before").unwrap());
        }
    }

    /// Ends the server side of the connections to `url`'s database whose backend pid is in
    /// `pids` (all but the caller's when empty), as a restart does, and waits until they are
    /// gone.
    fn terminate(url: &str, pids: &[i32]) {
        let mut admin = config(url).unwrap().connect(postgres::NoTls).unwrap();
        let chosen = "datname = current_database() AND pid <> pg_backend_pid() \
                      AND (cardinality($1::int[]) = 0 OR pid = ANY($1))";
        admin
            .execute(
                &format!("SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE {chosen}"),
                &[&pids],
            )
            .unwrap();
        let count = format!("SELECT count(*) FROM pg_stat_activity WHERE {chosen}");
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while admin.query_one(&count, &[&pids]).unwrap().get::<_, i64>(0) > 0 {
            assert!(std::time::Instant::now() < deadline, "backends still there");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }

    #[test]
    fn a_call_whose_connection_broke_just_now_runs_again() {
        let Some(url) = test_database::fresh("rerun") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        use crate::storage::TokenStore;
        // Every connection used just now: none is old enough to be checked before use.
        let leases: Vec<_> = (0..CONNECTIONS)
            .map(|_| store.pool.lease().unwrap())
            .collect();
        drop(leases);
        for _ in 0..2 * CONNECTIONS {
            assert!(!store.has_token("anyone").unwrap());
        }
        terminate(&url, &[]);
        for _ in 0..2 * CONNECTIONS {
            assert!(!store.has_token("anyone").unwrap());
        }
    }

    #[test]
    fn a_transaction_whose_connection_broke_fails_and_leaves_nothing() {
        let Some(url) = test_database::fresh("broken_tx") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        store
            .pool
            .run(|c| Ok(c.batch_execute("CREATE TABLE marks (n INT)")?))
            .unwrap();
        let mut lease = store.pool.lease().unwrap();
        let pid = lease
            .run(|c| {
                Ok(c.query_one("SELECT pg_backend_pid()", &[])?
                    .get::<_, i32>(0))
            })
            .unwrap();
        lease.begin().unwrap();
        lease
            .run(|c| Ok(c.execute("INSERT INTO marks VALUES (1)", &[]).map(|_| ())?))
            .unwrap();
        terminate(&url, &[pid]);
        // The rest of the transaction runs nowhere: not alone on a new connection.
        let err = lease
            .run(|c| Ok(c.execute("INSERT INTO marks VALUES (2)", &[]).map(|_| ())?))
            .unwrap_err()
            .to_string();
        assert!(err.contains("during a transaction"), "{err}");
        assert!(lease.commit().is_err());
        drop(lease);
        let marks = store
            .pool
            .run(|c| {
                Ok(c.query_one("SELECT count(*) FROM marks", &[])?
                    .get::<_, i64>(0))
            })
            .unwrap();
        assert_eq!(marks, 0);
    }

    #[test]
    fn a_database_that_stops_answering_for_a_while_is_waited_for() {
        let Some(url) = test_database::fresh("waits") else {
            return;
        };
        // A proxy in front of the test server that refuses connections for a second, as a
        // restarting server does.
        let target: std::net::SocketAddr = {
            let c = config(&url).unwrap();
            let host = match &c.get_hosts()[0] {
                postgres::config::Host::Tcp(h) => h.clone(),
                #[allow(unreachable_patterns)]
                _ => return,
            };
            format!("{host}:{}", c.get_ports()[0]).parse().unwrap()
        };
        let proxy = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = proxy.local_addr().unwrap().port();
        let through = url.replacen(&target.port().to_string(), &port.to_string(), 1);
        let refusing = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let refuse = refusing.clone();
        std::thread::spawn(move || {
            for client in proxy.incoming().flatten() {
                if refuse.load(std::sync::atomic::Ordering::SeqCst) {
                    drop(client);
                    continue;
                }
                let server = std::net::TcpStream::connect(target).unwrap();
                for (mut from, mut to) in [
                    (client.try_clone().unwrap(), server.try_clone().unwrap()),
                    (server, client),
                ] {
                    std::thread::spawn(move || {
                        let _ = std::io::copy(&mut from, &mut to);
                        let _ = to.shutdown(std::net::Shutdown::Both);
                    });
                }
            }
        });
        let store = PgStore::open(&through).unwrap();
        use crate::storage::TokenStore;
        assert!(!store.has_token("anyone").unwrap());
        refusing.store(true, std::sync::atomic::Ordering::SeqCst);
        terminate(&url, &[]);
        let back = refusing.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_secs(1));
            back.store(false, std::sync::atomic::Ordering::SeqCst);
        });
        let started = std::time::Instant::now();
        assert!(!store.has_token("anyone").unwrap());
        let waited = started.elapsed();
        assert!(
            waited >= std::time::Duration::from_millis(900) && waited < pool::RECONNECT_WAIT,
            "{waited:?}"
        );
    }

    #[test]
    fn tls_to_the_database_is_used_and_checked_as_sslmode_asks() {
        let Some(url) = test_database::fresh("tls") else {
            return;
        };
        let Some(ca) = std::env::var("SITAR_TEST_PG_CA")
            .ok()
            .filter(|v| !v.is_empty())
        else {
            println!("SKIPPED tls: SITAR_TEST_PG_CA is not set (the test Postgres has no TLS)");
            return;
        };
        let encrypted = |store: &PgStore| {
            store
                .pool
                .run(|c| {
                    let sql = "SELECT ssl FROM pg_stat_ssl WHERE pid = pg_backend_pid()";
                    Ok(c.query_one(sql, &[])?.get::<_, bool>(0))
                })
                .unwrap()
        };
        // libpq's default (prefer): encrypted, as the server offers it.
        assert!(encrypted(&PgStore::open(&url).unwrap()));
        assert!(!encrypted(
            &PgStore::open(&format!("{url}?sslmode=disable")).unwrap()
        ));
        let full = format!("{url}?sslmode=verify-full&sslrootcert={ca}");
        assert!(encrypted(&PgStore::open(&full).unwrap()));
        // The certificate is made out to 127.0.0.1, not to localhost: verify-ca takes it
        // there, verify-full does not.
        let by_name = url.replacen("127.0.0.1", "localhost", 1);
        let ca_only = format!("{by_name}?sslmode=verify-ca&sslrootcert={ca}");
        assert!(encrypted(&PgStore::open(&ca_only).unwrap()));
        let err = PgStore::open(&format!("{by_name}?sslmode=verify-full&sslrootcert={ca}"))
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("certificate"), "{err}");
        // Signed by another CA: refused, whatever the name.
        let other = tempfile::tempdir().unwrap();
        let other_ca = other.path().join("other-ca.pem");
        let mut params = rcgen::CertificateParams::new(vec!["127.0.0.1".into()]).unwrap();
        params.is_ca = rcgen::IsCa::Ca(rcgen::BasicConstraints::Unconstrained);
        let key = rcgen::KeyPair::generate().unwrap();
        std::fs::write(&other_ca, params.self_signed(&key).unwrap().pem()).unwrap();
        let err = PgStore::open(&format!(
            "{url}?sslmode=verify-ca&sslrootcert={}",
            other_ca.display()
        ))
        .err()
        .unwrap()
        .to_string();
        assert!(err.contains("certificate"), "{err}");
    }

    #[test]
    fn a_call_that_panics_fails_alone() {
        let Some(url) = test_database::fresh("panics") else {
            return;
        };
        let store = PgStore::open(&url).unwrap();
        // A column read as the wrong type panics inside rust-postgres.
        for _ in 0..2 * CONNECTIONS {
            let err = store
                .pool
                .run(|c| Ok(c.query_one("SELECT 'text'", &[])?.get::<_, i64>(0)))
                .unwrap_err();
            assert!(err.to_string().contains("without an answer"), "{err}");
        }
        use crate::storage::TokenStore;
        assert!(
            !store.has_token("anyone").unwrap(),
            "every thread still serves"
        );
    }

    #[test]
    fn a_busy_connection_thread_is_never_a_tokio_worker() {
        let Some(url) = test_database::fresh("runtime") else {
            return;
        };
        let store = std::sync::Arc::new(PgStore::open(&url).unwrap());
        use crate::storage::TokenStore;
        // Called from async tasks on both runtime flavours: no panic, right answers.
        let multi = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .build()
            .unwrap();
        let s = store.clone();
        multi.block_on(async move {
            let tasks: Vec<_> = (0..16)
                .map(|i| {
                    let s = s.clone();
                    tokio::spawn(async move { s.has_token(&format!("t{i}")).unwrap() })
                })
                .collect();
            for t in tasks {
                assert!(!t.await.unwrap());
            }
        });
        let single = tokio::runtime::Builder::new_current_thread()
            .build()
            .unwrap();
        single.block_on(async { assert!(!store.has_token("x").unwrap()) });
    }
}
