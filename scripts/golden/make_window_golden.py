#!/usr/bin/env python3
"""Golden data for a session with 20-frame windows and the rotational estimate (angle_deg).

evo's RPE (rotation angle in degrees, delta 20 frames, all pairs) over every pair i < j of
the estimator's golden trials (trial i the reference, associated as evo does), per reference
start stamp aggregated with scipy.stats.trim_mean(values, 0.3): what `sitar estimate --delta
20 -r angle_deg` and the backend's results for a session with `window_frames: 20,
pose_relation: "angle_deg"` must both equal to 1e-9 (rust/cli/tests/window_golden.rs).

Reads rust/estimator/tests/data/trials/trial_00..07.txt (made by make_goldens.py, whose
pairwise loop this reuses with its delta set to 20); writes
rust/server/tests/data/golden_window_20_angle_deg.json:
  {"trials": [names], "delta": 20, "t_max_diff": 0.01, "pose_relation": "angle_deg",
   "setting": "trim_mean_30", "windows": [[start_ns, value_deg, pairs, std_deg], ...]}

Usage: python3 scripts/golden/make_window_golden.py   (needs: pip install evo numpy scipy)
"""
import json
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import make_goldens  # noqa: E402  (its main() only runs as a script)

ROOT = pathlib.Path(__file__).resolve().parents[2]
TRIALS = ROOT / "rust" / "estimator" / "tests" / "data" / "trials"
OUT = ROOT / "rust" / "server" / "tests" / "data" / "golden_window_20_angle_deg.json"
DELTA = 20
SETTING = "trim_mean_30"


def main():
    names = [f"trial_{i:02d}.txt" for i in range(8)]
    files = {name: make_goldens.read_tum(TRIALS / name) for name in names}
    make_goldens.DELTA = DELTA  # golden_estimate reads the module's delta
    golden = make_goldens.golden_estimate(files, names, "angle_deg")
    assert golden["delta"] == DELTA
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps({
        "trials": names,
        "delta": DELTA,
        "t_max_diff": golden["t_max_diff"],
        "pose_relation": "angle_deg",
        "setting": SETTING,
        "windows": golden["settings"][SETTING],
    }, separators=(",", ":")) + "\n")
    print(f"wrote {OUT.relative_to(ROOT)}: {len(golden['settings'][SETTING])} windows")


if __name__ == "__main__":
    main()
