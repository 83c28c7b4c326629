//! `sitar token create|list|revoke --data DIR` (or `--database URL`): the backend's access
//! tokens, in its database (they work while `sitar serve` runs on the same data directory or
//! Postgres database).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use sitar_server::{Role, create_token_at, list_tokens_at, revoke_token_at};

/// Where the tokens are: a data directory's database, or the Postgres of `serve --database`.
#[derive(clap::Args, Debug)]
#[group(required = true, multiple = false)]
struct Database {
    /// Data directory of `sitar serve`.
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// The Postgres database of `sitar serve --database` (postgres://…; PG* variables fill
    /// in what it leaves out).
    #[arg(long, value_name = "URL")]
    database: Option<String>,
}

impl Database {
    /// What the messages name: the directory, or "the database" (never its URL's password).
    fn name(&self) -> String {
        match &self.data {
            Some(dir) => format!("--data {}", dir.display()),
            None => "--database".to_owned(),
        }
    }

    fn data(&self) -> PathBuf {
        self.data.clone().unwrap_or_else(|| PathBuf::from("."))
    }
}

/// Manages the backend's access tokens (only their hashes are stored).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example: sitar token create --data sitar-data --role app --name lab-phone-1"
)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Subcommand, Debug)]
enum Command {
    /// Makes a token and prints it as the only line on stdout (shown this once).
    Create {
        #[command(flatten)]
        data: Database,
        /// `app` (its own sessions), `admin` (everything) or `worker` (a playback host:
        /// the /v1/worker/ routes only).
        #[arg(long, value_parser = parse_role)]
        role: Role,
        /// A name for logs and `sitar token list` (letters, digits, `._-`).
        #[arg(long)]
        name: String,
    },
    /// Lists the tokens: name, role, created, last used (never the token).
    List {
        #[command(flatten)]
        data: Database,
    },
    /// Revokes the token NAME: its next request is refused.
    Revoke {
        #[command(flatten)]
        data: Database,
        /// The token's name.
        name: String,
    },
}

fn parse_role(s: &str) -> Result<Role, String> {
    s.parse()
}

/// `2026-12-02T03:04:05Z` of ms since the epoch.
fn utc(ms: i64) -> String {
    jiff::Timestamp::from_millisecond(ms)
        .map(|t| t.round(jiff::Unit::Second).unwrap_or(t).to_string())
        .unwrap_or_else(|_| format!("{ms} ms"))
}

pub fn run(args: Args) -> Result<()> {
    match args.command {
        Command::Create { data, role, name } => {
            let token = create_token_at(&data.data(), data.database.as_deref(), role, &name)
                .with_context(|| format!("sitar token create {}", data.name()))?;
            println!("{token}");
        }
        Command::List { data } => {
            let tokens = list_tokens_at(&data.data(), data.database.as_deref())
                .with_context(|| format!("sitar token list {}", data.name()))?;
            println!("{:<24} {:<6} {:<21} last used", "name", "role", "created");
            for t in tokens {
                println!(
                    "{:<24} {:<6} {:<21} {}",
                    t.name,
                    t.role.as_str(),
                    utc(t.created_ms),
                    t.last_used_ms.map_or_else(|| "never".to_owned(), utc)
                );
            }
        }
        Command::Revoke { data, name } => {
            if !revoke_token_at(&data.data(), data.database.as_deref(), &name)
                .with_context(|| format!("sitar token revoke {}", data.name()))?
            {
                bail!("no token named {name:?} in {}", data.name());
            }
            eprintln!("sitar token: revoked {name:?}");
        }
    }
    Ok(())
}
