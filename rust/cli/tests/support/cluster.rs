//! The cluster services the real-process tests need (`scripts/cluster-services start`): the
//! database and bucket they name, a fresh database per test, and `sitar serve` instances on
//! them.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::process::Serving;

/// A fresh database and a bucket prefix of its own for one test: what its instances share.
pub struct Cluster {
    pub database: String,
    pub store: String,
}

impl Cluster {
    /// Test `test`'s fresh database and bucket prefix (`…/TEST-PID`, `_` as `-`), or `None`
    /// after printing SKIPPED.
    pub fn fresh(test: &str) -> Option<Cluster> {
        let (url, store) = services(test)?;
        let database = fresh_database(test, &url)?;
        let prefix = test.replace('_', "-");
        Some(Cluster {
            database,
            store: format!("{store}/{prefix}-{}", std::process::id()),
        })
    }

    /// An instance on this cluster: `sitar serve` with sim playback ([`Serving::sim`]) in
    /// folder `data`, `--database DATABASE --store STORE` and `extra` arguments.
    pub fn serve(&self, data: &Path, extra: &[&str]) -> Serving {
        let mut args = vec!["--database", &self.database, "--store", &self.store];
        args.extend_from_slice(extra);
        Serving::sim(data, &args)
    }
}

/// The test services' URLs, or `None` after printing SKIPPED.
pub fn services(test: &str) -> Option<(String, String)> {
    let var = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
    match (var("SITAR_TEST_DATABASE_URL"), var("SITAR_TEST_S3_URL")) {
        (Some(db), Some(s3)) => Some((db, s3)),
        _ => {
            println!(
                "SKIPPED {test}: SITAR_TEST_DATABASE_URL and SITAR_TEST_S3_URL are not both set \
                 (scripts/cluster-services start)"
            );
            None
        }
    }
}

/// A fresh database on the test server (made with `psql`), or `None` after printing SKIPPED.
pub fn fresh_database(test: &str, url: &str) -> Option<String> {
    let name = format!("sitar_cli_{test}_{}", std::process::id());
    let made = Command::new("psql")
        .args([url, "-q", "-c"])
        .arg(format!("DROP DATABASE IF EXISTS {name} WITH (FORCE)"))
        .args(["-c", &format!("CREATE DATABASE {name}")])
        .output();
    match made {
        Ok(out) if out.status.success() => {
            let base = url.rsplit_once('/').map_or(url, |(base, _)| base);
            Some(format!("{base}/{name}"))
        }
        Ok(out) => {
            println!(
                "SKIPPED {test}: psql cannot make a database: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            None
        }
        Err(e) => {
            println!("SKIPPED {test}: no psql: {e}");
            None
        }
    }
}

/// The test Postgres' data folder (`SITAR_TEST_PG_DATA`), or `None` after printing SKIPPED.
pub fn postgres_data(test: &str) -> Option<PathBuf> {
    match std::env::var_os("SITAR_TEST_PG_DATA").filter(|v| !v.is_empty()) {
        Some(dir) => Some(PathBuf::from(dir)),
        None => {
            println!(
                "SKIPPED {test}: SITAR_TEST_PG_DATA is not set (scripts/cluster-services start)"
            );
            None
        }
    }
}

/// Restarts the test Postgres (`pg_ctl restart -m fast`, as its owner when we are root, as
/// `scripts/cluster-services` started it): every connection to it breaks once.
pub fn restart_postgres(data: &Path) {
    let pg_ctl = "/usr/lib/postgresql/15/bin/pg_ctl";
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    let mut command = if root {
        let mut c = Command::new("runuser");
        c.args(["-u", "postgres", "--", pg_ctl]);
        c
    } else {
        Command::new(pg_ctl)
    };
    // Its log goes where it went: the server must not keep our pipe open.
    let log = data.parent().unwrap_or(data).join("server.log");
    let out = command
        .args(["restart", "-m", "fast", "-w", "-t", "60", "-D"])
        .arg(data)
        .arg("-l")
        .arg(log)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("pg_ctl");
    assert!(
        out.status.success(),
        "pg_ctl restart: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}
