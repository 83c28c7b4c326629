#!/usr/bin/env python3
"""Golden result for `sitar evaluate`, made independently with evo, numpy, scipy and scikit-learn.

The paper's protocol (section 3.3): the true error of each window is the mean evo RPE
(translation part, delta 10 frames, all pairs) of the set-A trials against the ground truth;
the estimate is SiTAR's pairwise statistic over the first k set-B trials (evo RPE for each pair
i < j, trial i the reference, then numpy/scipy statistics); both are classified with the
paper's three class boundaries and scored with scikit-learn (accuracy, macro F1; sensitivity =
macro recall over the classes present in the truth; specificity from the confusion matrix).

Usage (from the repository root; needs `pip install evo numpy scipy scikit-learn`):
    python3 rust/cli/tests/golden/make_evaluate_golden.py [--sitar target/debug/sitar]
With --sitar the input data (rust/cli/tests/golden/eval/) is regenerated first.
Writes rust/cli/tests/golden/eval/expected.json.
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile
from collections import defaultdict

import numpy as np
import scipy.stats
from sklearn.metrics import accuracy_score, confusion_matrix, f1_score, recall_score

from evo.core import metrics, sync
from evo.tools import file_interface

HERE = pathlib.Path(__file__).resolve().parent
EVAL = HERE / "eval"
DELTA = 10
MAX_DIFF = 0.01
COUNTS = [2, 3, 4]
SETTINGS = ["mean", "median", "trim_mean_10", "trim_mean_20", "trim_mean_30", "trim_mean_40",
            "mean_inliers"]
BOUNDARIES = [(0.05, 0.10), (0.02, 0.10), (0.02, 0.05)]

sys.path.insert(0, str(HERE))
from make_goldens import seconds_copy  # noqa: E402


def regenerate(sitar):
    if EVAL.exists():
        shutil.rmtree(EVAL)
    subprocess.run([sitar, "simulate", "--out", str(EVAL), "--trials", "4", "--seconds", "4",
                    "--seed", "11", "--second-set", "--drop-frames", "0.03"], check=True)
    for extra in ("scene.json", "recording.sitarsim"):
        (EVAL / extra).unlink()


def load(path, tmp):
    copy = tmp / (path.parent.name + "_" + path.name)
    seconds_copy(path, copy)
    return file_interface.read_tum_trajectory_file(str(copy))


def rpe_by_start(reference, estimate):
    """{start stamp ns: error} of evo's RPE, reference = first trajectory."""
    ref, est = sync.associate_trajectories(reference, estimate, max_diff=MAX_DIFF)
    rpe = metrics.RPE(metrics.PoseRelation.translation_part, delta=DELTA,
                      delta_unit=metrics.Unit.frames, all_pairs=True)
    rpe.process_data((ref, est))
    return {int(round(ref.timestamps[j - DELTA] * 1e9)): float(e)
            for j, e in zip(rpe.delta_ids, rpe.error)}


def statistic(values, setting):
    v = np.asarray(values)
    if setting == "mean":
        return float(np.mean(v))
    if setting == "median":
        return float(np.median(v))
    if setting.startswith("trim_mean_"):
        return float(scipy.stats.trim_mean(v, int(setting[-2:]) / 100))
    q1, q3 = np.percentile(v, [25, 75])
    iqr = q3 - q1
    return float(np.mean(v[(v >= q1 - 1.5 * iqr) & (v <= q3 + 1.5 * iqr)]))


def classify(errors, bounds):
    return [2 if e >= bounds[1] else 1 if e >= bounds[0] else 0 for e in errors]


def scores(truth, predicted):
    labels = sorted(set(truth) | set(predicted))
    cm = confusion_matrix(truth, predicted, labels=labels)
    total = cm.sum()
    specificity = []
    for c in range(len(labels)):
        tp = cm[c, c]
        fp = cm[:, c].sum() - tp
        fn = cm[c, :].sum() - tp
        tn = total - tp - fp - fn
        if tn + fp > 0:
            specificity.append(tn / (tn + fp))
    return {
        "accuracy": float(accuracy_score(truth, predicted)),
        "macro_f1": float(f1_score(truth, predicted, average="macro", zero_division=0)),
        "sensitivity": float(recall_score(truth, predicted, labels=sorted(set(truth)),
                                          average="macro", zero_division=0)),
        "specificity": float(np.mean(specificity)) if specificity else None,
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sitar", help="sitar binary: regenerate the input data first")
    args = parser.parse_args()
    if args.sitar:
        regenerate(args.sitar)
    natural = lambda p: int(p.stem.split("_")[-1])
    files_a = sorted((EVAL / "trials").glob("*.txt"), key=natural)
    files_b = sorted((EVAL / "trials-b").glob("*.txt"), key=natural)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        gt = load(EVAL / "ground_truth.txt", tmp)
        set_a = [load(f, tmp) for f in files_a]
        set_b = [load(f, tmp) for f in files_b]
    sums = defaultdict(list)
    for trial in set_a:
        for start, e in rpe_by_start(gt, trial).items():
            sums[start].append(e)
    truth = {k: float(np.mean(v)) for k, v in sums.items()}
    results = []
    for k in COUNTS:
        pair_values = defaultdict(list)
        for i in range(k):
            for j in range(i + 1, k):
                for start, e in rpe_by_start(set_b[i], set_b[j]).items():
                    pair_values[start].append(e)
        for setting in SETTINGS:
            keys = sorted(pair_values)
            estimate = [statistic(pair_values[s], setting) for s in keys]
            true = [truth[s] for s in keys]  # same stamps here: nearest match is exact
            for bounds in BOUNDARIES:
                row = {"boundaries_m": list(bounds), "setting": setting, "trials": k,
                       "windows": len(keys)}
                row.update(scores(classify(true, bounds), classify(estimate, bounds)))
                results.append(row)
    out = {"trial_counts": COUNTS, "truth_windows": len(truth), "results": results}
    (EVAL / "expected.json").write_text(json.dumps(out, indent=1) + "\n")
    print(f"{len(results)} rows, {len(truth)} true windows")


if __name__ == "__main__":
    main()
