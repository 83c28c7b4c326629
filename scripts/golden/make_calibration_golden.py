#!/usr/bin/env python3
"""Golden data for the calibration (rust/core/src/calibration/, rust/estimator/src/calibration*.rs).

Writes rust/estimator/tests/data/golden_calibration.json:
  motion      one synthetic run (stamps, positions, quaternions x y z w) and, per window of
              DELTA frames, what numpy and scipy make of it: path length, rotation angle
              (scipy Rotation.magnitude of q_k^-1 q_k+delta, degrees), straight-line
              displacement, jitter = mean over inner frames of |v+ - v-| / ((t[i+1]-t[i-1])/2)
  sequences   three sequences of synthetic windows (spread, path, rotation, displacement,
              jitter, truth; deterministic seed)
  smoothed    scipy.ndimage.uniform_filter1d(size=2h+1, mode="nearest") of each feature
  model       numpy.linalg.lstsq of ln(truth) on [1, ln(f + offset) for the 5 features],
              center = mean of the fit, stretch = (std(ln truth)/std(fit))**spread_match
  interval    cross-conformal by sequence: each sequence's residuals under the model fitted on
              the other two, quantiles (numpy linear) at (1 -/+ coverage)/2
  loso        per held-out sequence the calibrated value of its first windows, by the
              calibration fitted on the other two (its interval cross-conformal over them)
  candidates  every candidate feature set of a model from several runs, its mean held-out
              Spearman's rho (scipy.stats.spearmanr), and the one kept: the fewest features
              within 0.01 of the best rho (the higher rho on a tie)
Usage: python3 scripts/golden/make_calibration_golden.py (needs numpy and scipy).
"""
import json
import pathlib

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.spatial.transform import Rotation
from scipy.stats import spearmanr

OUT = pathlib.Path(__file__).resolve().parents[2] / "rust" / "estimator" / "tests" / "data"
H, SPREAD_MATCH, COVERAGE, DELTA = 3, 0.45, 0.8, 10
FEATURES = ("spread", "path_m", "rotation_deg", "displacement_m", "jitter_mps2")
NAMES = {"spread": "ln_spread", "path_m": "ln_path_m", "rotation_deg": "ln_rotation_deg",
         "displacement_m": "ln_displacement_m", "jitter_mps2": "ln_jitter_mps2"}
OFFSETS = {"spread": 1e-3, "path_m": 1e-3, "rotation_deg": 0.1, "displacement_m": 1e-3, "jitter_mps2": 1e-2}
MOTION_SETS = [("path_m", "rotation_deg"), ("path_m", "rotation_deg", "displacement_m"),
               ("path_m", "rotation_deg", "jitter_mps2"),
               ("path_m", "rotation_deg", "displacement_m", "jitter_mps2")]
CANDIDATES = [("spread",)] + MOTION_SETS + [("spread",) + m for m in MOTION_SETS]
rng = np.random.default_rng(20261207)


def motion_golden(n=60):
    stamps = np.cumsum(rng.integers(30_000_000, 40_000_000, n))
    positions = np.cumsum(rng.normal(0, 0.02, (n, 3)), axis=0)
    rot = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.03, (n, 3)), axis=0))
    quats = rot.as_quat()  # x y z w
    t = stamps * 1e-9
    rows = []
    for k in range(n - DELTA):
        e = k + DELTA
        steps = np.diff(positions[k:e + 1], axis=0)
        path = np.linalg.norm(steps, axis=1).sum()
        angle = (rot[k].inv() * rot[e]).magnitude()
        v = steps / np.diff(t[k:e + 1])[:, None]
        dt = (t[k + 2:e + 1] - t[k:e - 1]) / 2
        jitter = np.mean(np.linalg.norm(np.diff(v, axis=0), axis=1) / dt)
        rows.append([path, np.degrees(angle), np.linalg.norm(positions[e] - positions[k]), jitter])
    return {"stamps": stamps.tolist(), "positions": positions.tolist(), "quaternions": quats.tolist(),
            "delta": DELTA, "windows": rows}


def sequence(n, scale):
    path = np.abs(rng.normal(0.5, 0.2, n)) + 0.01
    rotation = np.abs(rng.normal(4.0, 3.0, n))
    displacement = path * rng.uniform(0.3, 1.0, n)
    jitter = rng.lognormal(np.log(0.5), 0.7, n)
    spread = np.abs(rng.lognormal(np.log(0.03), 0.6, n))
    truth = (scale * spread ** 0.3 * path ** 0.3 * (path / displacement) ** 0.4 * jitter ** 0.2
             * (rotation + 0.1) ** 0.1 * rng.lognormal(0, 0.4, n))
    return {"spread": spread, "path_m": path, "rotation_deg": rotation, "displacement_m": displacement,
            "jitter_mps2": jitter, "truth": truth}


def smooth(seq):
    return {k: uniform_filter1d(seq[k], size=2 * H + 1, mode="nearest") for k in FEATURES}


def design(f, features):
    return np.c_[np.ones_like(f["spread"])] if not features else \
        np.c_[np.ones_like(f["spread"]), np.column_stack([np.log(f[k] + OFFSETS[k]) for k in features])]


def fit(seqs, features):
    x = np.vstack([design(s["smoothed"], features) for s in seqs])
    y = np.concatenate([np.log(s["truth"]) for s in seqs])
    w, *_ = np.linalg.lstsq(x, y, rcond=None)
    fitted = x @ w
    return w, fitted.mean(), (y.std() / fitted.std()) ** SPREAD_MATCH


def log_value(model, f, features):
    w, center, stretch = model
    return center + (design(f, features) @ w - center) * stretch


def calibration(seqs, features):
    model = fit(seqs, features)
    residuals = []
    for i, held in enumerate(seqs):
        partial = fit([s for j, s in enumerate(seqs) if j != i], features)
        residuals.append(np.log(held["truth"]) - log_value(partial, held["smoothed"], features))
    r = np.concatenate(residuals)
    lo, hi = np.quantile(r, [(1 - COVERAGE) / 2, (1 + COVERAGE) / 2])
    return model, lo, hi


seqs = [sequence(n, scale) for n, scale in ((160, 1.0), (140, 1.3), (150, 0.7))]
for s in seqs:
    s["smoothed"] = smooth(s)
ALL = FEATURES
model, lo, hi = calibration(seqs, ALL)
loso = []
for i, held in enumerate(seqs):
    inner = calibration([s for j, s in enumerate(seqs) if j != i], ALL)
    value = log_value(inner[0], held["smoothed"], ALL)
    loso.append({"value": np.exp(value[:20]).tolist(), "lower": np.exp(value[:20] + inner[1]).tolist(),
                 "upper": np.exp(value[:20] + inner[2]).tolist()})
candidates = []
for features in CANDIDATES:
    rhos = []
    for i, held in enumerate(seqs):
        inner = calibration([s for j, s in enumerate(seqs) if j != i], features)
        rhos.append(spearmanr(held["truth"], np.exp(log_value(inner[0], held["smoothed"], features)))[0])
    candidates.append({"features": [NAMES[f] for f in features], "spearman": float(np.mean(rhos))})
best = max(c["spearman"] for c in candidates)
kept = min((i for i, c in enumerate(candidates) if c["spearman"] >= best - 0.01),
           key=lambda i: (len(candidates[i]["features"]), -candidates[i]["spearman"]))
doc = {
    "smoothing_windows": H, "spread_match": SPREAD_MATCH, "coverage": COVERAGE,
    "motion": motion_golden(),
    "sequences": [{k: s[k].tolist() for k in FEATURES + ("truth",)}
                  | {"smoothed": {k: v.tolist() for k, v in s["smoothed"].items()}} for s in seqs],
    "features": [NAMES[f] for f in ALL],
    "coefficients": model[0].tolist(), "center": float(model[1]), "stretch": float(model[2]),
    "log_lower": float(lo), "log_upper": float(hi),
    "loso": loso,
    "candidates": candidates, "kept": kept,
}
(OUT / "golden_calibration.json").write_text(json.dumps(doc) + "\n")
print("wrote", OUT / "golden_calibration.json", "kept", candidates[kept])
