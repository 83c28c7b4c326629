//! `sitar migrate --data DIR --database URL --store URL`: moves an embedded installation
//! (tokens, sessions, venues, usage counters and every session's files) into the cluster
//! stores, verifies it (rows per table, SHA-256 of every file on both sides) and prints a
//! summary; exits non-zero naming what differs. Safe to run again after an interruption.

use std::path::PathBuf;

use anyhow::{Result, bail};
#[cfg(feature = "cluster")]
use sitar_server::{MigrateOptions, migrate};

/// Moves an embedded installation into Postgres and an S3-compatible bucket. DIR/sitar.db and
/// DIR/sessions are copied and verified for `sitar serve --database URL --store URL`; stop the
/// server on DIR first (a running one is refused). Run it again after an interruption: what
/// is there and equal is skipped, what is partial is copied again. (A build with the
/// `cluster` feature: `cargo build --release -p sitar-cli --features cluster`.)
#[derive(clap::Args, Debug)]
#[command(after_help = "Example:
  sitar migrate --data sitar-data --database postgres://sitar@db.lab:5432/sitar \\
                --store s3://sitar-bucket/lab
then: sitar serve --data instance-a --database … --store … (the same tokens work; the admin
token stays in sitar-data/admin.token). Endpoint and credentials of the bucket come from
AWS_ENDPOINT_URL, AWS_REGION, AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY (AWS_ALLOW_HTTP for a
plain-HTTP endpoint); the PG* variables fill in what the database URL leaves out.")]
pub struct Args {
    /// Data directory of the embedded installation (`sitar serve --data DIR`).
    #[arg(long, value_name = "DIR")]
    data: PathBuf,
    /// The Postgres database to copy into (postgres://USER@HOST:PORT/DATABASE): empty, or
    /// written by an earlier run of this copy.
    #[arg(long, value_name = "URL")]
    database: String,
    /// The bucket to copy the files into (s3://BUCKET/PREFIX).
    #[arg(long, value_name = "URL")]
    store: String,
}

/// Without the cluster backends there is nothing to copy into: say how to get a build that
/// has them.
#[cfg(not(feature = "cluster"))]
pub fn run(args: Args) -> Result<()> {
    let _ = (args.data, args.database, args.store);
    bail!("sitar migrate: {}", sitar_server::NO_CLUSTER)
}

#[cfg(feature = "cluster")]
pub fn run(args: Args) -> Result<()> {
    let options = MigrateOptions {
        data: args.data,
        database: args.database,
        store: args.store,
    };
    let summary = migrate(&options, &mut |line| println!("{line}"))?;
    println!("{summary}");
    if !summary.verified() {
        bail!(
            "the cluster stores differ from {} (listed above)",
            options.data.display()
        );
    }
    if summary.copied_nothing() {
        println!("nothing copied: everything was in the cluster stores already");
    }
    Ok(())
}
