#!/usr/bin/env python3
"""Golden result for `sitar evaluate` over several sequences, made independently with evo,
numpy, scipy and scikit-learn.

Per sequence the paper's protocol as in make_evaluate_golden.py (evo RPE, scipy/numpy
statistics, scikit-learn scores). Across sequences: the mean of each score (numpy), the median
estimate/truth ratio per sequence and over all windows (numpy.median), Spearman's rank
correlation (scipy.stats.spearmanr), the calibration scale exp(mean(ln truth - ln estimate))
on the training sequences and the held-out accuracy and F1 with it (scikit-learn), the
threshold sweep's ROC AUC and average precision (sklearn.metrics.roc_auc_score,
average_precision_score) and the percentile-bootstrap interval of the mean accuracy
(scipy.stats.bootstrap, 20000 resamples: equal to ours within Monte Carlo error).

Usage (from the repository root; needs `pip install evo numpy scipy scikit-learn`):
    python3 rust/cli/tests/golden/make_sequences_golden.py [--sitar target/debug/sitar]
With --sitar the input data (rust/cli/tests/golden/sequences/) is regenerated first.
Writes rust/cli/tests/golden/sequences/expected.json.
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
from sklearn.metrics import accuracy_score, average_precision_score, f1_score, roc_auc_score

HERE = pathlib.Path(__file__).resolve().parent
SEQS = HERE / "sequences"
sys.path.insert(0, str(HERE))
from make_evaluate_golden import (BOUNDARIES, SETTINGS, classify, load, rpe_by_start,  # noqa: E402
                                  scores, statistic)

COUNTS = [2, 4]
TRAIN = 2
SWEEP = [0.02, 0.05, 0.10]


def regenerate(sitar):
    if SEQS.exists():
        shutil.rmtree(SEQS)
    subprocess.run([sitar, "simulate", "--out", str(SEQS), "--sequences", "4", "--trials", "4",
                    "--seconds", "3", "--seed", "5", "--tracker", "ransac"], check=True)
    for seq in SEQS.glob("seq_*"):
        for extra in ("scene.json", "recording.sitarsim"):
            (seq / extra).unlink()


def sequence(seq, tmp):
    natural = lambda p: int(p.stem.split("_")[-1])
    gt = load(seq / "ground_truth.txt", tmp)
    set_a = [load(f, tmp) for f in sorted((seq / "trials").glob("*.txt"), key=natural)]
    set_b = [load(f, tmp) for f in sorted((seq / "trials-b").glob("*.txt"), key=natural)]
    sums = defaultdict(list)
    for trial in set_a:
        for start, e in rpe_by_start(gt, trial).items():
            sums[start].append(e)
    truth = {k: float(np.mean(v)) for k, v in sums.items()}
    out = {}
    for k in COUNTS:
        pair_values = defaultdict(list)
        for i in range(k):
            for j in range(i + 1, k):
                for start, e in rpe_by_start(set_b[i], set_b[j]).items():
                    pair_values[start].append(e)
        keys = sorted(pair_values)
        for setting in SETTINGS:
            out[(setting, k)] = (np.array([truth[s] for s in keys]),
                                 np.array([statistic(pair_values[s], setting) for s in keys]))
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sitar", help="sitar binary: regenerate the input data first")
    args = parser.parse_args()
    if args.sitar:
        regenerate(args.sitar)
    seqs = sorted(SEQS.glob("seq_*"))
    with tempfile.TemporaryDirectory() as tmp:
        data = [sequence(s, pathlib.Path(tmp)) for s in seqs]
    averaged, agreement, calibration, sweeps = [], [], [], []
    for k in COUNTS:
        for setting in SETTINGS:
            per = [d[(setting, k)] for d in data]
            ratios = [float(np.median(e[t > 0] / t[t > 0])) for t, e in per]
            ranks = [float(scipy.stats.spearmanr(t, e).statistic) for t, e in per]
            all_t = np.concatenate([t for t, _ in per])
            all_e = np.concatenate([e for _, e in per])
            agreement.append({"setting": setting, "trials": k, "median_ratio": ratios,
                              "spearman": ranks,
                              "pooled_median_ratio": float(np.median(all_e[all_t > 0] / all_t[all_t > 0]))})
            train_t = np.concatenate([t for t, _ in per[:TRAIN]])
            train_e = np.concatenate([e for _, e in per[:TRAIN]])
            ok = (train_t >= 1e-6) & (train_e >= 1e-6)  # below: rounding noise
            scale = float(np.exp(np.mean(np.log(train_t[ok]) - np.log(train_e[ok]))))
            for bounds in BOUNDARIES:
                s = [scores(classify(t, bounds), classify(e, bounds)) for t, e in per]
                accuracy = [x["accuracy"] for x in s]
                ci = scipy.stats.bootstrap((np.array(accuracy),), np.mean, n_resamples=20000,
                                           confidence_level=0.95, method="percentile",
                                           random_state=1).confidence_interval
                averaged.append({"setting": setting, "trials": k, "boundaries_m": list(bounds),
                                 "accuracy": float(np.mean(accuracy)),
                                 "macro_f1": float(np.mean([x["macro_f1"] for x in s])),
                                 "sensitivity": float(np.mean([x["sensitivity"] for x in s])),
                                 "specificity": float(np.mean([x["specificity"] for x in s
                                                                       if x["specificity"] is not None])),
                                 "accuracy_low": float(ci.low), "accuracy_high": float(ci.high)})
                held = per[TRAIN:]
                raw = [(accuracy_score(classify(t, bounds), classify(e, bounds)),
                        f1_score(classify(t, bounds), classify(e, bounds), average="macro",
                                 zero_division=0)) for t, e in held]
                cal = [(accuracy_score(classify(t, bounds), classify(e * scale, bounds)),
                        f1_score(classify(t, bounds), classify(e * scale, bounds),
                                 average="macro", zero_division=0)) for t, e in held]
                calibration.append({"setting": setting, "trials": k, "boundaries_m": list(bounds),
                                    "scale": scale,
                                    "raw": [float(np.mean([r[0] for r in raw])),
                                            float(np.mean([r[1] for r in raw]))],
                                    "calibrated": [float(np.mean([c[0] for c in cal])),
                                                   float(np.mean([c[1] for c in cal]))]})
            if k == COUNTS[-1]:
                for b in SWEEP:
                    y = all_t >= b
                    row = {"setting": setting, "trials": k, "boundary_m": b,
                           "positives": int(y.sum()), "negatives": int((~y).sum())}
                    both = 0 < y.sum() < len(y)
                    row["roc_auc"] = float(roc_auc_score(y, all_e)) if both else None
                    row["average_precision"] = (float(average_precision_score(y, all_e))
                                                if y.sum() > 0 else None)
                    sweeps.append(row)
    out = {"sequences": len(seqs), "trial_counts": COUNTS, "train": TRAIN, "averaged": averaged,
           "agreement": agreement, "calibration": calibration, "sweeps": sweeps}
    (SEQS / "expected.json").write_text(json.dumps(out, indent=1) + "\n")
    print(f"{len(seqs)} sequences, {len(averaged)} averaged rows")


if __name__ == "__main__":
    main()
