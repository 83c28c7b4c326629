//! The Postgres the tests use: `SITAR_TEST_DATABASE_URL` (set by `scripts/cluster-services`).
//! Each test gets a database of its own, made fresh, so tests run in parallel.

/// A fresh, empty database named after `test` on the test server, or `None` (after printing
/// `SKIPPED`) when `SITAR_TEST_DATABASE_URL` is not set or the server does not answer.
pub(crate) fn fresh(test: &str) -> Option<String> {
    let Some(url) = std::env::var("SITAR_TEST_DATABASE_URL")
        .ok()
        .filter(|u| !u.is_empty())
    else {
        println!(
            "SKIPPED {test}: SITAR_TEST_DATABASE_URL is not set (scripts/cluster-services start)"
        );
        return None;
    };
    let name = format!("sitar_test_{test}_{}", std::process::id());
    let made = (|| -> Result<(), postgres::Error> {
        let mut admin = super::config(&url)
            .map_err(|e| panic!("SITAR_TEST_DATABASE_URL: {e}"))
            .unwrap()
            .connect(postgres::NoTls)?;
        admin.batch_execute(&format!("DROP DATABASE IF EXISTS {name} WITH (FORCE)"))?;
        admin.batch_execute(&format!("CREATE DATABASE {name}"))
    })();
    if let Err(e) = made {
        println!("SKIPPED {test}: the test database at {url} does not answer: {e}");
        return None;
    }
    let base = url.rsplit_once('/').map_or(url.as_str(), |(base, _)| base);
    Some(format!("{base}/{name}"))
}
