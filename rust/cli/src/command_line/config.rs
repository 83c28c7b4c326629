//! Command lines before clap sees them: SiTAR's older `sitar ape|rpe REF EST` form (no
//! format subcommand; `-i` gave the format) and evo's `-c/--config FILE.json`, whose keys
//! become flags appended after the command line's own, so that they win as in evo.

use std::ffi::OsString;

use anyhow::{Context, Result, bail};

/// evo's format subcommands.
const FORMATS: [&str; 6] = ["tum", "euroc", "kitti", "bag", "bag2", "mcap"];

/// The command line with the legacy form rewritten and the config file expanded.
pub fn expand(argv: Vec<OsString>, command: &clap::Command) -> Result<Vec<OsString>> {
    let argv = legacy_format(argv);
    with_config(argv, command)
}

/// `sitar ape REF EST [-i FORMAT] …` → `sitar ape FORMAT REF EST … --time_unit auto`: the
/// older form keeps SiTAR's stamp rule (integers above 10^11 are nanoseconds).
fn legacy_format(mut argv: Vec<OsString>) -> Vec<OsString> {
    let is = |k: usize, names: &[&str]| {
        argv.get(k)
            .and_then(|a| a.to_str())
            .is_some_and(|a| names.contains(&a))
    };
    if !is(1, &["ape", "rpe"]) {
        return argv;
    }
    let Some(first) = argv.get(2).and_then(|a| a.to_str()) else {
        return argv;
    };
    if FORMATS.contains(&first) || first.starts_with('-') {
        return argv;
    }
    let mut format = OsString::from("tum");
    let mut k = 3;
    while k < argv.len() {
        let arg = argv[k].to_string_lossy().into_owned();
        if ["-i", "--input-format", "--input_format"].contains(&arg.as_str()) && k + 1 < argv.len()
        {
            format = argv.remove(k + 1);
            argv.remove(k);
            continue;
        }
        if let Some(v) = arg
            .strip_prefix("--input-format=")
            .or_else(|| arg.strip_prefix("--input_format="))
        {
            format = v.into();
            argv.remove(k);
            continue;
        }
        k += 1;
    }
    let timed = format != "kitti";
    argv.insert(2, format);
    let has_unit = argv.iter().any(|a| {
        let a = a.to_string_lossy();
        a.starts_with("--time_unit") || a.starts_with("--time-unit")
    });
    if timed && !has_unit {
        argv.extend(["--time_unit".into(), "auto".into()]);
    }
    argv
}

/// The (sub)command whose options the config file may set: `ape tum`, `traj`, `res` …
fn target<'a>(command: &'a clap::Command, argv: &[OsString]) -> Option<&'a clap::Command> {
    let tool = command.find_subcommand(argv.get(1)?.to_str()?)?;
    if tool.has_subcommands() {
        tool.find_subcommand(argv.get(2)?.to_str()?)
    } else {
        Some(tool)
    }
}

fn with_config(mut argv: Vec<OsString>, command: &clap::Command) -> Result<Vec<OsString>> {
    let Some(k) = argv.iter().position(|a| {
        let a = a.to_string_lossy();
        a == "-c" || a == "--config" || a.starts_with("--config=")
    }) else {
        return Ok(argv);
    };
    let Some(target) = target(command, &argv) else {
        return Ok(argv);
    };
    let arg = argv[k].to_string_lossy().into_owned();
    let path = match arg.strip_prefix("--config=") {
        Some(p) => p.to_owned(),
        None => argv
            .get(k + 1)
            .map(|p| p.to_string_lossy().into_owned())
            .context("-c/--config needs a .json file")?,
    };
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{path}: cannot read the config file"))?;
    let object: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&text).with_context(|| format!("{path}: not a JSON object"))?;
    for (key, value) in object {
        let known = target
            .get_arguments()
            .find(|a| a.get_long() == Some(key.as_str()) || a.get_id() == key.as_str());
        let Some(known) = known.and_then(|a| a.get_long()) else {
            eprintln!("[WARNING] {path}: '{key}' is not an option of this command; ignored");
            continue;
        };
        let flag = OsString::from(format!("--{known}"));
        match value {
            serde_json::Value::Bool(true) => argv.push(flag),
            serde_json::Value::Bool(false) | serde_json::Value::Null => {}
            serde_json::Value::Array(values) => {
                argv.push(flag);
                argv.extend(values.iter().map(|v| OsString::from(plain(v))));
            }
            serde_json::Value::Object(_) => bail!("{path}: '{key}' must not be an object"),
            v => {
                argv.push(flag);
                argv.push(plain(&v).into());
            }
        }
    }
    Ok(argv)
}

/// A JSON scalar as a command-line word.
fn plain(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(v: &[&str]) -> Vec<OsString> {
        v.iter().map(OsString::from).collect()
    }

    #[test]
    fn legacy_form_gets_a_format() {
        assert_eq!(
            legacy_format(words(&["sitar", "ape", "a.txt", "b.txt", "-a"])),
            words(&[
                "sitar",
                "ape",
                "tum",
                "a.txt",
                "b.txt",
                "-a",
                "--time_unit",
                "auto"
            ])
        );
        assert_eq!(
            legacy_format(words(&["sitar", "rpe", "a", "b", "-i", "kitti", "-d", "3"])),
            words(&["sitar", "rpe", "kitti", "a", "b", "-d", "3"])
        );
        let evo = words(&["sitar", "ape", "euroc", "a", "b"]);
        assert_eq!(legacy_format(evo.clone()), evo);
        let help = words(&["sitar", "ape", "--help"]);
        assert_eq!(legacy_format(help.clone()), help);
    }
}
