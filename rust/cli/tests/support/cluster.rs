//! The cluster services the real-process tests need (`scripts/cluster-services start`): the
//! database and bucket they name, and a fresh database per test.

use std::process::Command;

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
