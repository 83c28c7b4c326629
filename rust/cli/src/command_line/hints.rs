//! Hints in usage errors that name what the usage shows: clap suggests the closest spelling
//! among a flag's names and aliases (`--all-pairs` for `--all-pair`), while the usage and
//! `--help` show the flag's own name (`--all_pairs`); the hint is rewritten to that name.

use clap::error::{ContextKind, ContextValue};

/// `error` with every suggested flag that is an alias replaced by the flag's own long name.
pub fn canonical_suggestions(mut error: clap::Error, command: &clap::Command) -> clap::Error {
    let Some(ContextValue::String(suggested)) = error.get(ContextKind::SuggestedArg).cloned()
    else {
        return error;
    };
    let Some(alias) = suggested.strip_prefix("--") else {
        return error;
    };
    if let Some(long) = long_of_alias(command, alias) {
        error.insert(
            ContextKind::SuggestedArg,
            ContextValue::String(format!("--{long}")),
        );
    }
    error
}

/// The long name of the first flag (depth first through the subcommands) with `alias`.
fn long_of_alias(command: &clap::Command, alias: &str) -> Option<String> {
    command
        .get_arguments()
        .find(|a| a.get_all_aliases().is_some_and(|all| all.contains(&alias)))
        .and_then(|a| a.get_long().map(str::to_owned))
        .or_else(|| {
            command
                .get_subcommands()
                .find_map(|sub| long_of_alias(sub, alias))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[derive(Parser)]
    struct Demo {
        #[arg(long = "all_pairs", alias = "all-pairs")]
        all_pairs: bool,
        #[arg(long = "align")]
        align: bool,
    }

    fn hint(args: &[&str]) -> String {
        let error = Demo::try_parse_from(args).err().unwrap();
        canonical_suggestions(error, &Demo::command()).to_string()
    }

    #[test]
    fn suggests_the_name_the_usage_shows() {
        let text = hint(&["demo", "--all-pair"]);
        assert!(text.contains("'--all_pairs'"), "{text}");
        assert!(!text.contains("--all-pairs"), "{text}");
        assert!(hint(&["demo", "--alig"]).contains("'--align'"));
    }
}
