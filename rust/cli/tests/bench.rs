//! `sitar bench DIR`: rpg_trajectory_evaluation's results layout and the plain tree, built in
//! a temporary directory from the real runs of `../shared/data/real-runs`; the numbers
//! against the estimator's numpy golden (`scripts/golden/make_relative_golden.py`), the two
//! layouts against each other, the four formats, and clear errors.

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::run::{fails, ok};

/// Relative tolerance against numpy.
const TOLERANCE: f64 = 1e-9;

fn real() -> Option<PathBuf> {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real-runs/euroc-vio");
    if dir.join("MH_04/ground_truth.txt").is_file() {
        Some(dir)
    } else {
        eprintln!("SKIPPED: {} is missing", dir.display());
        None
    }
}

fn golden_case(name: &str) -> Value {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../estimator/tests/data/golden_relative.json");
    let golden: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    golden["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == name)
        .unwrap_or_else(|| panic!("no golden case {name}"))
        .clone()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn assert_close(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() <= TOLERANCE * want.abs().max(1.0),
        "{what}: got {got}, numpy {want}"
    );
}

const CFG: &str = "align_type: posyaw\nalign_num_frames: -1\n";

/// rpg's layout: laptop/vislam/laptop_vislam_SEQ with runs 0 and 7 of each sequence.
fn rpg_tree(real: &Path, root: &Path) {
    for seq in ["MH_04", "MH_05", "V1_02"] {
        let folder = root.join(format!("laptop/vislam/laptop_vislam_{seq}"));
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::copy(
            real.join(seq).join("ground_truth.txt"),
            folder.join("stamped_groundtruth.txt"),
        )
        .unwrap();
        for (i, run) in [0, 7].iter().enumerate() {
            std::fs::copy(
                real.join(format!("{seq}/runs/run{run}.txt")),
                folder.join(format!("stamped_traj_estimate{i}.txt")),
            )
            .unwrap();
        }
        std::fs::write(folder.join("eval_cfg.yaml"), CFG).unwrap();
    }
}

/// The plain tree with the same files.
fn plain_tree(real: &Path, root: &Path) {
    std::fs::create_dir_all(root.join("gt")).unwrap();
    for seq in ["MH_04", "MH_05", "V1_02"] {
        std::fs::copy(
            real.join(seq).join("ground_truth.txt"),
            root.join(format!("gt/{seq}.txt")),
        )
        .unwrap();
        let folder = root.join(format!("vislam/{seq}"));
        std::fs::create_dir_all(&folder).unwrap();
        for (i, run) in [0, 7].iter().enumerate() {
            std::fs::copy(
                real.join(format!("{seq}/runs/run{run}.txt")),
                folder.join(format!("run{i}.txt")),
            )
            .unwrap();
        }
        std::fs::write(folder.join("eval_cfg.yaml"), CFG).unwrap();
    }
}

fn json(dir: &Path) -> Value {
    serde_json::from_str(&ok(&["bench", dir.to_str().unwrap(), "--format", "json"])).unwrap()
}

#[test]
fn rpg_layout_equals_numpy_over_two_runs() {
    let Some(real) = real() else { return };
    let tmp = tempfile::tempdir().unwrap();
    rpg_tree(&real, tmp.path());
    let doc = json(tmp.path());
    let results = doc["results"].as_array().unwrap();
    assert_eq!(results.len(), 3);
    for (r, seq) in results.iter().zip(["MH_04", "MH_05", "V1_02"]) {
        assert_eq!(r["algorithm"], "vislam");
        assert_eq!(r["sequence"], seq);
        assert_eq!(r["trials"], 2);
        assert_eq!(r["align_type"], "posyaw");
        let (a, b) = (
            golden_case(&format!("{seq}_run0_posyaw")),
            golden_case(&format!("{seq}_run7_posyaw")),
        );
        let (ra, rb) = (f(&a["ape_rmse_m"]), f(&b["ape_rmse_m"]));
        let ape = &r["ape_rmse"];
        assert_close("ape mean", f(&ape["mean"]), (ra + rb) / 2.0);
        assert_close("ape std", f(&ape["std"]), (ra - rb).abs() / 2.0);
        assert_close("ape min", f(&ape["min"]), ra.min(rb));
        assert_close("ape max", f(&ape["max"]), ra.max(rb));
        // Relative errors pooled over the two runs (rpg's MulTrajError): counts add, the
        // mean is the count-weighted mean, min and max are the extremes.
        for (k, at) in r["relative"].as_array().unwrap().iter().enumerate() {
            let (la, lb) = (&a["lengths"][k], &b["lengths"][k]);
            assert_eq!(f(&at["length_m"]), f(&la["length_m"]));
            let (na, nb) = (f(&la["count"]), f(&lb["count"]));
            assert_eq!(f(&at["samples"]), na + nb);
            for m in [
                "trans_m",
                "trans_percent",
                "rot_deg",
                "yaw_deg",
                "roll_pitch_deg",
            ] {
                let (sa, sb) = (&la["stats"][m], &lb["stats"][m]);
                let what = format!("{seq} {} m {m}", f(&at["length_m"]));
                let want = (f(&sa["mean"]) * na + f(&sb["mean"]) * nb) / (na + nb);
                assert_close(&format!("{what} mean"), f(&at[m]["mean"]), want);
                let rmse = ((f(&sa["rmse"]).powi(2) * na + f(&sb["rmse"]).powi(2) * nb)
                    / (na + nb))
                    .sqrt();
                assert_close(&format!("{what} rmse"), f(&at[m]["rmse"]), rmse);
                assert_close(
                    &format!("{what} min"),
                    f(&at[m]["min"]),
                    f(&sa["min"]).min(f(&sb["min"])),
                );
                assert_close(
                    &format!("{what} max"),
                    f(&at[m]["max"]),
                    f(&sa["max"]).max(f(&sb["max"])),
                );
            }
        }
        assert!(f(&r["drift"]["t_err_percent"]["mean"]) > 0.0);
    }
}

#[test]
fn plain_tree_equals_rpg_layout_and_formats_agree() {
    let Some(real) = real() else { return };
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    rpg_tree(&real, a.path());
    plain_tree(&real, b.path());
    let strip = |mut v: Value| {
        for r in v["results"].as_array_mut().unwrap() {
            r.as_object_mut().unwrap().remove("ground_truth");
            r.as_object_mut().unwrap().remove("runs");
        }
        v
    };
    assert_eq!(strip(json(a.path())), strip(json(b.path())));

    let dir = b.path().to_str().unwrap();
    let markdown = ok(&["bench", dir]);
    let lines: Vec<&str> = markdown.lines().collect();
    assert_eq!(lines.len(), 2 + 3, "{markdown}");
    assert!(
        lines[0].starts_with("| algorithm | sequence | runs | APE RMSE (m) | rel. trans. 10 % (%)")
    );
    assert!(
        lines[2].starts_with("| vislam | MH_04 | 2 | 0.198 ± 0.029 |"),
        "{}",
        lines[2]
    );
    let latex = ok(&["bench", dir, "--format", "latex"]);
    assert!(
        latex.starts_with("\\begin{tabular}") && latex.contains("MH\\_04"),
        "{latex}"
    );
    assert!(latex.contains("$\\pm$"));
    let csv = ok(&["bench", dir, "--format", "csv", "--lengths", "8,16"]);
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    assert!(rows.iter().all(|r| r.len() == rows[0].len()));
    assert_eq!(rows[0][..3], ["algorithm", "sequence", "trials"]);
    assert!(rows[0].contains(&"rel_trans_percent_mean_8m"));
    let out = b.path().join("table.json");
    ok(&[
        "bench",
        dir,
        "--format",
        "json",
        "--lengths",
        "8,16",
        "-o",
        out.to_str().unwrap(),
    ]);
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    assert_eq!(doc["results"][0]["lengths_m"][0].as_f64(), Some(8.0));
    // The box plots: APE RMSE, and per sequence a box per algorithm and length.
    let plot = b.path().join("plots").join("bench.svg");
    std::fs::create_dir_all(plot.parent().unwrap()).unwrap();
    ok(&["bench", dir, "--save_plot", plot.to_str().unwrap()]);
    for page in ["ape_rmse", "MH_04_trans_percent", "V1_02_yaw_deg"] {
        let file = b.path().join(format!("plots/bench_{page}.svg"));
        assert!(file.is_file(), "{page}");
    }
    // Without eval_cfg.yaml: rpg's default, Sim(3) on every pose.
    std::fs::remove_file(b.path().join("vislam/MH_04/eval_cfg.yaml")).unwrap();
    assert_eq!(json(b.path())["results"][0]["align_type"], "sim3");
}

#[test]
fn bad_trees_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let e = fails(&["bench", dir.to_str().unwrap()]);
    assert!(e.contains("no results found"), "{e}");
    let folder = dir.join("p/alg/p_alg_seq");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(
        folder.join("stamped_groundtruth.txt"),
        "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n",
    )
    .unwrap();
    let e = fails(&["bench", dir.to_str().unwrap()]);
    assert!(e.contains("no stamped_traj_estimate"), "{e}");
    std::fs::write(
        folder.join("stamped_traj_estimate0.txt"),
        "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n",
    )
    .unwrap();
    std::fs::write(
        folder.join("eval_cfg.yaml"),
        "align_type: posyaw\nalign_num_frames: all\n",
    )
    .unwrap();
    let e = fails(&["bench", dir.to_str().unwrap()]);
    assert!(e.contains("eval_cfg.yaml:2: align_num_frames"), "{e}");
    let plain = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(plain.path().join("gt")).unwrap();
    std::fs::create_dir_all(plain.path().join("alg/seq")).unwrap();
    let e = fails(&["bench", plain.path().to_str().unwrap()]);
    assert!(e.contains("no ground truth for sequence seq"), "{e}");
}
