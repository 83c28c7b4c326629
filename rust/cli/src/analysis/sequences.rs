//! Sequences with ground truth, as `sitar evaluate` and `sitar calibrate` take them.
//!
//! A sequence is a folder with `ground_truth.txt` and either `runs/` (repeated runs of one
//! SLAM, natural order: the first ⌈N/2⌉ are set A, the truth, the rest set B, the estimate;
//! `--split K` puts K runs in set A) or `trials/` (set A) and `trials-b/` (set B), the layout
//! `sitar simulate` writes. A folder without `ground_truth.txt` stands for the sequences in
//! it, in natural order.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::io::input;

/// The fewest runs a `runs/` folder may hold (two for the truth, two for the estimate).
pub const MIN_RUNS: usize = 4;
/// The largest number of sequences read at once (each is a full trial set in memory in turn).
const MAX_SEQUENCES: usize = 10_000;

/// One sequence's files.
#[derive(Debug, Clone)]
pub struct SequenceInput {
    /// The folder as given.
    pub name: String,
    /// `ground_truth.txt`.
    pub ground_truth: PathBuf,
    /// Where set A comes from (`runs/` or `trials/`), for messages.
    pub dir_a: PathBuf,
    /// Where set B comes from (`runs/` or `trials-b/`), for messages.
    pub dir_b: PathBuf,
    /// Set A's files, in order.
    pub set_a: Vec<PathBuf>,
    /// Set B's files, in order.
    pub set_b: Vec<PathBuf>,
}

/// Expands SEQUENCE arguments into sequences; `split` is `--split`.
pub fn sequence_inputs(dirs: &[PathBuf], split: Option<usize>) -> Result<Vec<SequenceInput>> {
    if dirs.is_empty() {
        bail!(
            "give SEQUENCE directories (each with ground_truth.txt and runs/ or trials/ + trials-b/)"
        );
    }
    let mut out = Vec::new();
    for dir in dirs {
        if dir.join("ground_truth.txt").is_file() {
            out.push(one(dir, split)?);
            continue;
        }
        let entries =
            std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?;
        let mut subdirs: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.join("ground_truth.txt").is_file())
            .collect();
        if subdirs.is_empty() {
            bail!(
                "{}: neither a sequence (no ground_truth.txt) nor a directory of sequences",
                dir.display()
            );
        }
        subdirs.sort_by_key(|p| natural_key(p));
        for sub in &subdirs {
            out.push(one(sub, split)?);
        }
        if out.len() > MAX_SEQUENCES {
            bail!("more than {MAX_SEQUENCES} sequences given");
        }
    }
    Ok(out)
}

/// One sequence folder.
fn one(dir: &Path, split: Option<usize>) -> Result<SequenceInput> {
    let name = dir.display().to_string();
    let ground_truth = dir.join("ground_truth.txt");
    let runs = dir.join("runs");
    if runs.is_dir() {
        let files = input::trial_files(&runs)?;
        let n = files.len();
        if n < MIN_RUNS {
            bail!(
                "{}: {n} runs, at least {MIN_RUNS} are needed (set A for the truth, set B for the estimate, two each)",
                runs.display()
            );
        }
        let k = split.unwrap_or(n.div_ceil(2));
        if k < 1 || k + 2 > n {
            bail!(
                "--split {k}: set A needs at least 1 of the {n} runs of {} and set B at least 2",
                runs.display()
            );
        }
        return Ok(SequenceInput {
            name,
            ground_truth,
            dir_a: runs.clone(),
            dir_b: runs,
            set_a: files[..k].to_vec(),
            set_b: files[k..].to_vec(),
        });
    }
    let (dir_a, dir_b) = (dir.join("trials"), dir.join("trials-b"));
    if !dir_a.is_dir() || !dir_b.is_dir() {
        bail!("{name}: has ground_truth.txt but neither runs/ nor trials/ and trials-b/",);
    }
    if split.is_some() {
        bail!("{name}: --split applies to a runs/ folder; this sequence has trials/ and trials-b/");
    }
    Ok(SequenceInput {
        name,
        ground_truth,
        set_a: input::trial_files(&dir_a)?,
        set_b: input::trial_files(&dir_b)?,
        dir_a,
        dir_b,
    })
}

/// Sorts `seq_2` before `seq_10`.
fn natural_key(path: &Path) -> (String, u64) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let digits: String = name
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect();
    let number = digits
        .chars()
        .rev()
        .collect::<String>()
        .parse()
        .unwrap_or(0);
    (
        name.trim_end_matches(|c: char| c.is_ascii_digit())
            .to_owned(),
        number,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_runs(dir: &Path, n: usize) {
        std::fs::create_dir_all(dir.join("runs")).unwrap();
        std::fs::write(dir.join("ground_truth.txt"), "0 0 0 0 0 0 0 1\n").unwrap();
        for i in 0..n {
            std::fs::write(dir.join(format!("runs/run{i}.txt")), "0 0 0 0 0 0 0 1\n").unwrap();
        }
    }

    #[test]
    fn runs_split_in_natural_order() {
        let dir = std::env::temp_dir().join(format!("sitar-seq-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        write_runs(&dir.join("a"), 11);
        let s = sequence_inputs(&[dir.join("a")], None).unwrap();
        let names = |files: &[PathBuf]| -> Vec<String> {
            files
                .iter()
                .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
                .collect()
        };
        // ⌈11/2⌉ = 6 runs in set A, run10 after run9.
        assert_eq!(
            names(&s[0].set_a),
            [
                "run0.txt", "run1.txt", "run2.txt", "run3.txt", "run4.txt", "run5.txt"
            ]
        );
        assert_eq!(
            names(&s[0].set_b),
            ["run6.txt", "run7.txt", "run8.txt", "run9.txt", "run10.txt"]
        );
        let s = sequence_inputs(&[dir.join("a")], Some(2)).unwrap();
        assert_eq!((s[0].set_a.len(), s[0].set_b.len()), (2, 9));
        let err = sequence_inputs(&[dir.join("a")], Some(10))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("--split 10") && err.contains("set B at least 2"),
            "{err}"
        );
        write_runs(&dir.join("b"), 3);
        let err = sequence_inputs(&[dir.join("b")], None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("3 runs, at least 4"), "{err}");
        // A folder of sequences: each one that has ground truth.
        std::fs::remove_dir_all(dir.join("b")).unwrap();
        write_runs(&dir.join("c"), 4);
        let s = sequence_inputs(std::slice::from_ref(&dir), None).unwrap();
        assert_eq!(s.len(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
