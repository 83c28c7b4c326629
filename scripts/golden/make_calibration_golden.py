#!/usr/bin/env python3
"""Golden data for sitar-estimator's calibration fit (rust/estimator/src/calibration*.rs).

Writes rust/estimator/tests/data/golden_calibration.json: three sequences of synthetic
windows (statistic, path, rotation, truth; deterministic seed), and what numpy and scipy make
of them with the model the calibration documents:
  smoothed    scipy.ndimage.uniform_filter1d(size=2h+1, mode="nearest") of each feature
  model       numpy.linalg.lstsq of ln(truth) on [1, ln(s+1e-3), ln(p+1e-3), ln(r+0.1)],
              center = mean of the fit, stretch = (std(ln truth)/std(fit))**spread_match
  interval    cross-conformal by sequence: each sequence's residuals under the model fitted on
              the other two, quantiles (numpy linear) at (1 -/+ coverage)/2
  loso        per held-out sequence the calibrated value of its first windows, by the
              calibration fitted on the other two (its interval cross-conformal over them)
Usage: python3 scripts/golden/make_calibration_golden.py (needs numpy and scipy).
"""
import json
import pathlib

import numpy as np
from scipy.ndimage import uniform_filter1d

OUT = pathlib.Path(__file__).resolve().parents[2] / "rust" / "estimator" / "tests" / "data"
H, SPREAD_MATCH, COVERAGE = 3, 0.45, 0.8
OFFSETS = (1e-3, 1e-3, 0.1)
rng = np.random.default_rng(20261206)


def sequence(n, scale):
    path = np.abs(rng.normal(0.5, 0.2, n)) + 0.01
    rotation = np.abs(rng.normal(4.0, 3.0, n))
    statistic = np.abs(rng.lognormal(np.log(0.03), 0.6, n))
    truth = scale * statistic ** 0.4 * path ** 0.3 * (rotation + 0.1) ** 0.1 * rng.lognormal(0, 0.4, n)
    return {"statistic": statistic, "path_m": path, "rotation_deg": rotation, "truth": truth}


def smooth(seq):
    return {k: uniform_filter1d(seq[k], size=2 * H + 1, mode="nearest") for k in ("statistic", "path_m", "rotation_deg")}


def design(f):
    return np.c_[np.ones_like(f["statistic"]), np.log(f["statistic"] + OFFSETS[0]),
                 np.log(f["path_m"] + OFFSETS[1]), np.log(f["rotation_deg"] + OFFSETS[2])]


def fit(seqs):
    x = np.vstack([design(s["smoothed"]) for s in seqs])
    y = np.concatenate([np.log(s["truth"]) for s in seqs])
    w, *_ = np.linalg.lstsq(x, y, rcond=None)
    fitted = x @ w
    center = fitted.mean()
    stretch = (y.std() / fitted.std()) ** SPREAD_MATCH
    return w, center, stretch


def log_value(model, f):
    w, center, stretch = model
    return center + (design(f) @ w - center) * stretch


def calibration(seqs):
    model = fit(seqs)
    residuals = []
    for i, held in enumerate(seqs):
        partial = fit([s for j, s in enumerate(seqs) if j != i])
        residuals.append(np.log(held["truth"]) - log_value(partial, held["smoothed"]))
    r = np.concatenate(residuals)
    lo, hi = np.quantile(r, [(1 - COVERAGE) / 2, (1 + COVERAGE) / 2])
    return model, lo, hi


seqs = [sequence(n, scale) for n, scale in ((160, 1.0), (140, 1.3), (150, 0.7))]
for s in seqs:
    s["smoothed"] = smooth(s)
model, lo, hi = calibration(seqs)
loso = []
for i, held in enumerate(seqs):
    inner = calibration([s for j, s in enumerate(seqs) if j != i])
    value = log_value(inner[0], held["smoothed"])
    loso.append({"value": np.exp(value[:20]).tolist(), "lower": np.exp(value[:20] + inner[1]).tolist(),
                 "upper": np.exp(value[:20] + inner[2]).tolist()})
doc = {
    "smoothing_windows": H, "spread_match": SPREAD_MATCH, "coverage": COVERAGE,
    "sequences": [{k: s[k].tolist() for k in ("statistic", "path_m", "rotation_deg", "truth")}
                  | {"smoothed": {k: v.tolist() for k, v in s["smoothed"].items()}} for s in seqs],
    "coefficients": model[0].tolist(), "center": float(model[1]), "stretch": float(model[2]),
    "log_lower": float(lo), "log_upper": float(hi),
    "loso": loso,
}
(OUT / "golden_calibration.json").write_text(json.dumps(doc) + "\n")
print("wrote", OUT / "golden_calibration.json")
