#!/usr/bin/env python3
"""Golden data for repeated runs (`sitar ape|drift FORMAT REF EST1 EST2 ...`): each run's
result and numpy's mean, median, min, max and std (ddof 0) of each statistic over the runs.

On ../shared/data/real-runs/euroc-vio/MH_04 (ground_truth.txt against runs/run0..4.txt, TUM):
  ape     evo 1.38's APE (translation part, SE(3) Umeyama alignment: `evo_ape tum GT RUN -a`)
          per run, its statistics rmse, mean, median, std, min, max, sse
  drift   the KITTI devkit's drift (make_drift_goldens.py's numpy implementation), lengths
          1..8 m, a start every 10 poses, speed from stamps: t_err_percent, r_err_deg_per_m
Writes rust/cli/tests/golden/multirun/expected.json (the runs stay in the shared folder).

Usage: python3 scripts/golden/make_multirun_goldens.py   (needs: pip install evo numpy scipy)
"""
import json
import pathlib
import sys

import numpy as np
from evo.core import metrics, sync
from evo.tools import file_interface

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import make_drift_goldens as devkit  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "rust" / "cli" / "tests" / "golden" / "multirun"
SEQ = ROOT.parent / "shared" / "data" / "real-runs" / "euroc-vio" / "MH_04"
RUNS = [f"runs/run{k}.txt" for k in range(5)]
STATS = ["rmse", "mean", "median", "std", "min", "max", "sse"]


def across(values):
    v = np.array(values, dtype=float)
    return {
        "mean": float(np.mean(v)),
        "median": float(np.median(v)),
        "min": float(np.min(v)),
        "max": float(np.max(v)),
        "std": float(np.std(v)),
    }


def ape_runs():
    trials = []
    for run in RUNS:
        ref = file_interface.read_tum_trajectory_file(str(SEQ / "ground_truth.txt"))
        est = file_interface.read_tum_trajectory_file(str(SEQ / run))
        ref, est = sync.associate_trajectories(ref, est, max_diff=0.01)
        est.align(ref, correct_scale=False)
        ape = metrics.APE(metrics.PoseRelation.translation_part)
        ape.process_data((ref, est))
        stats = ape.get_all_statistics()
        trials.append({"estimate": run, "statistics": {k: float(stats[k]) for k in STATS}})
    return {
        "args": ["ape", "tum", "ground_truth.txt", *RUNS, "-a", "--format", "json"],
        "trials": trials,
        "across_trials": {k: across([t["statistics"][k] for t in trials]) for k in STATS},
    }


def drift_runs():
    stamps_gt, gt = devkit.read_tum(SEQ / "ground_truth.txt")
    lengths = [float(k) for k in range(1, 9)]
    trials = []
    for run in RUNS:
        stamps_run, poses = devkit.read_tum(SEQ / run)
        ids_gt, ids_run = devkit.associate(stamps_gt, stamps_run)
        t = stamps_gt[ids_gt]
        result = devkit.drift(
            [gt[i] for i in ids_gt],
            [poses[i] for i in ids_run],
            lengths,
            10,
            lambda a, b: t[b] - t[a],
            devkit.speed_bins(2.0),
            2.0,
        )
        del result["segment_list"]
        trials.append({"estimate": run, **result})
    names = ["t_err_percent", "r_err_deg_per_m"]
    return {
        "args": ["drift", "tum", "ground_truth.txt", *RUNS, "--lengths", "1,2,3,4,5,6,7,8",
                 "--format", "json"],
        "trials": trials,
        "across_trials": {k: across([t[k] for t in trials]) for k in names},
    }


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    expected = {"sequence": "real-runs/euroc-vio/MH_04", "ape": ape_runs(), "drift": drift_runs()}
    with open(OUT / "expected.json", "w") as f:
        json.dump(expected, f, indent=1)
        f.write("\n")
    for name in ["ape", "drift"]:
        print(name, json.dumps(expected[name]["across_trials"])[:200])


if __name__ == "__main__":
    main()
