//! `sitar bench`'s two result trees: rpg_trajectory_evaluation's
//! `PLATFORM/ALG/PLATFORM_ALG_DATASET/{stamped_groundtruth.txt, stamped_traj_estimate{i}.txt,
//! eval_cfg.yaml}` and a plain `ALG/SEQ/runN.txt` + `gt/SEQ.txt`; finding the cells
//! (algorithm × sequence), their runs and their alignment.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use sitar_estimator::{RpgAlignType, RpgAlignment};

/// One algorithm on one sequence: the ground truth, the runs, the alignment.
#[derive(Debug, Clone)]
pub struct Cell {
    pub algorithm: String,
    pub sequence: String,
    pub ground_truth: PathBuf,
    pub runs: Vec<PathBuf>,
    pub alignment: RpgAlignment,
}

/// The cells under `dir`, sorted by algorithm then sequence. `default` is the alignment of a
/// cell without an `eval_cfg.yaml`.
pub fn discover(dir: &Path, default: RpgAlignment) -> Result<Vec<Cell>> {
    if !dir.is_dir() {
        bail!("{}: not a directory", dir.display());
    }
    let mut cells = if dir.join("gt").is_dir() {
        plain(dir, default)?
    } else {
        rpg(dir, default)?
    };
    if cells.is_empty() {
        bail!(
            "{}: no results found: expected rpg_trajectory_evaluation's \
             PLATFORM/ALG/PLATFORM_ALG_DATASET/stamped_groundtruth.txt (+ \
             stamped_traj_estimate{{i}}.txt) or ALG/SEQ/runN.txt with gt/SEQ.txt",
            dir.display()
        );
    }
    cells.sort_by(|a, b| (&a.algorithm, &a.sequence).cmp(&(&b.algorithm, &b.sequence)));
    Ok(cells)
}

/// The subdirectories of `dir`, sorted by name.
fn subdirs(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for entry in
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot read", dir.display()))?
    {
        let path = entry
            .with_context(|| format!("{}: cannot read", dir.display()))?
            .path();
        if path.is_dir() {
            out.push(path);
        }
    }
    out.sort();
    Ok(out)
}

fn name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// `.txt` files in `dir` whose stem is `prefix` followed by a number, by that number.
fn numbered(dir: &Path, prefix: &str) -> Result<Vec<PathBuf>> {
    let mut found: Vec<(u64, PathBuf)> = Vec::new();
    for entry in
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot read", dir.display()))?
    {
        let path = entry
            .with_context(|| format!("{}: cannot read", dir.display()))?
            .path();
        let Some(stem) = path
            .extension()
            .is_some_and(|e| e == "txt")
            .then(|| path.file_stem())
            .flatten()
            .map(|s| s.to_string_lossy().into_owned())
        else {
            continue;
        };
        if let Some(k) = stem.strip_prefix(prefix).and_then(|n| n.parse().ok()) {
            found.push((k, path));
        }
    }
    found.sort();
    Ok(found.into_iter().map(|(_, p)| p).collect())
}

/// rpg's tree: `dir` is the results directory (holding PLATFORM folders), a PLATFORM folder,
/// an ALG folder or one result folder; every folder with a `stamped_groundtruth.txt` at most
/// three levels down is a cell.
fn rpg(dir: &Path, default: RpgAlignment) -> Result<Vec<Cell>> {
    let mut folders = Vec::new();
    let mut level = vec![dir.to_path_buf()];
    for _ in 0..4 {
        let mut next = Vec::new();
        for d in level {
            if d.join("stamped_groundtruth.txt").is_file() {
                folders.push(d);
            } else {
                next.extend(subdirs(&d)?);
            }
        }
        level = next;
    }
    let platforms: std::collections::BTreeSet<String> = folders
        .iter()
        .map(|f| {
            f.parent()
                .and_then(Path::parent)
                .map(name)
                .unwrap_or_default()
        })
        .collect();
    folders
        .into_iter()
        .map(|folder| {
            let alg = folder.parent().map(name).unwrap_or_default();
            let platform = folder
                .parent()
                .and_then(Path::parent)
                .map(name)
                .unwrap_or_default();
            let full = name(&folder);
            let sequence = full
                .strip_prefix(&format!("{platform}_{alg}_"))
                .map(str::to_owned)
                .unwrap_or(full);
            let mut runs = numbered(&folder, "stamped_traj_estimate")?;
            if runs.is_empty() && folder.join("stamped_traj_estimate.txt").is_file() {
                runs.push(folder.join("stamped_traj_estimate.txt"));
            }
            if runs.is_empty() {
                bail!(
                    "{}: no stamped_traj_estimate{{i}}.txt or stamped_traj_estimate.txt",
                    folder.display()
                );
            }
            let cfg = folder.join("eval_cfg.yaml");
            let alignment = if cfg.is_file() {
                read_eval_cfg(&cfg)?
            } else {
                default
            };
            Ok(Cell {
                algorithm: if platforms.len() > 1 {
                    format!("{platform}/{alg}")
                } else {
                    alg
                },
                sequence,
                ground_truth: folder.join("stamped_groundtruth.txt"),
                runs,
                alignment,
            })
        })
        .collect()
}

/// The plain tree: `gt/SEQ.txt`, and `ALG/SEQ/runN.txt` (any `*.txt` with a trailing number)
/// with an optional `ALG/SEQ/eval_cfg.yaml`.
fn plain(dir: &Path, default: RpgAlignment) -> Result<Vec<Cell>> {
    let mut cells = Vec::new();
    for alg in subdirs(dir)? {
        if name(&alg) == "gt" {
            continue;
        }
        for seq in subdirs(&alg)? {
            let sequence = name(&seq);
            let ground_truth = dir.join("gt").join(format!("{sequence}.txt"));
            if !ground_truth.is_file() {
                bail!(
                    "{}: no ground truth for sequence {sequence} (expected {})",
                    seq.display(),
                    ground_truth.display()
                );
            }
            let runs = numbered(&seq, "run")?;
            if runs.is_empty() {
                bail!("{}: no runN.txt", seq.display());
            }
            let cfg = seq.join("eval_cfg.yaml");
            cells.push(Cell {
                algorithm: name(&alg),
                sequence,
                ground_truth,
                runs,
                alignment: if cfg.is_file() {
                    read_eval_cfg(&cfg)?
                } else {
                    default
                },
            });
        }
    }
    Ok(cells)
}

/// Reads rpg's `eval_cfg.yaml`.
pub fn read_eval_cfg(path: &Path) -> Result<RpgAlignment> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    parse_eval_cfg(&text).map_err(|e| anyhow::anyhow!("{}:{e}", path.display()))
}

/// Parses the two keys of an `eval_cfg.yaml` (`align_type: posyaw`, `align_num_frames: -1`):
/// a flat mapping of scalars; other keys are ignored, as rpg ignores them. Errors start with
/// the line number.
pub fn parse_eval_cfg(text: &str) -> Result<RpgAlignment, String> {
    let (mut align_type, mut num_frames) = (None, None);
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split_once(" #").map_or(raw, |(a, _)| a).trim();
        if line.is_empty() || line.starts_with('#') || line == "---" {
            continue;
        }
        let Some((key, value)) = line.split_once(':') else {
            return Err(format!("{}: expected `key: value`, got {raw:?}", k + 1));
        };
        let value = value.trim().trim_matches(|c| c == '\'' || c == '"');
        match key.trim() {
            "align_type" => {
                let parsed: RpgAlignType = value.parse().map_err(|_| {
                    format!(
                        "{}: align_type must be posyaw, se3, sim3 or none, got {value:?}",
                        k + 1
                    )
                })?;
                align_type = Some(parsed);
            }
            "align_num_frames" => {
                let n: i64 = value.parse().map_err(|_| {
                    format!(
                        "{}: align_num_frames must be an integer, got {value:?}",
                        k + 1
                    )
                })?;
                if n == 0 || n < -1 {
                    return Err(format!(
                        "{}: align_num_frames must be -1 (all) or positive, got {n}",
                        k + 1
                    ));
                }
                num_frames = Some(n);
            }
            _ => {}
        }
    }
    match (align_type, num_frames) {
        (Some(align_type), Some(num_frames)) => Ok(RpgAlignment {
            align_type,
            num_frames,
        }),
        (None, _) => Err("1: missing key align_type".into()),
        (_, None) => Err("1: missing key align_num_frames".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eval_cfg_keys_and_errors() {
        let cfg = parse_eval_cfg("# rpg\nalign_type: posyaw\nalign_num_frames: -1  # all\n");
        assert_eq!(
            cfg.unwrap(),
            RpgAlignment {
                align_type: RpgAlignType::PosYaw,
                num_frames: -1
            }
        );
        let e = parse_eval_cfg("align_type: affine\nalign_num_frames: 1\n").unwrap_err();
        assert!(e.starts_with("1: align_type"), "{e}");
        let e = parse_eval_cfg("align_type: se3\nalign_num_frames: many\n").unwrap_err();
        assert!(e.starts_with("2: align_num_frames"), "{e}");
        let e = parse_eval_cfg("align_type: se3\n").unwrap_err();
        assert!(e.contains("missing key align_num_frames"), "{e}");
        let e = parse_eval_cfg("align_type se3\n").unwrap_err();
        assert!(e.starts_with("1: expected"), "{e}");
    }
}
