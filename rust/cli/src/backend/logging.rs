//! The server's log on stderr: `2026-12-02T03:04:05.123Z INFO message`, level from
//! `--log-level`, else `RUST_LOG` (env_logger's filter syntax), else info.

use std::io::Write;

/// Installs the logger once (a second call is a no-op). Without a level, `RUST_LOG` decides;
/// our crates log at info by default, everything else at warn.
pub fn init(level: Option<log::LevelFilter>) {
    let mut builder = env_logger::Builder::new();
    match level {
        Some(level) => {
            builder.filter_level(log::LevelFilter::Warn.min(level));
            for ours in ["sitar_server", "sitar_client", "sitar"] {
                builder.filter_module(ours, level);
            }
        }
        None => match std::env::var("RUST_LOG") {
            Ok(filter) if !filter.trim().is_empty() => {
                builder.parse_filters(&filter);
            }
            _ => {
                builder.parse_filters("warn,sitar_server=info,sitar_client=info,sitar=info");
            }
        },
    }
    builder.format(|buf, record| {
        writeln!(
            buf,
            "{} {} {}",
            buf.timestamp_millis(),
            record.level(),
            record.args()
        )
    });
    let _ = builder.try_init();
}
