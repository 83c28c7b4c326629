//! `sitar token create|list|revoke --data DIR`: the backend's access tokens, in its database
//! (they work while `sitar serve` runs on the same data directory).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use sitar_server::{Role, create_token, list_tokens, revoke_token};

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
        /// Data directory of `sitar serve`.
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
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
        /// Data directory of `sitar serve`.
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
    },
    /// Revokes the token NAME: its next request is refused.
    Revoke {
        /// Data directory of `sitar serve`.
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
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
            let token = create_token(&data, role, &name)
                .with_context(|| format!("sitar token create --data {}", data.display()))?;
            println!("{token}");
        }
        Command::List { data } => {
            let tokens = list_tokens(&data)
                .with_context(|| format!("sitar token list --data {}", data.display()))?;
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
            if !revoke_token(&data, &name)
                .with_context(|| format!("sitar token revoke --data {}", data.display()))?
            {
                bail!("no token named {name:?} in {}", data.display());
            }
            eprintln!("sitar token: revoked {name:?}");
        }
    }
    Ok(())
}
