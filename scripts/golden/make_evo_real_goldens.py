#!/usr/bin/env python3
"""Golden outputs of evo 1.38.1 on real sample trajectories, for issue 26 (association and
stamps to the last digit).

1. Copies the real files of evo's own test data (TUM RGB-D fr1/xyz and fr2/desk, EuRoC
   V1_02; CC BY 4.0, see rust/cli/tests/golden/evo_real/data/README.md) from an evo checkout
   into rust/cli/tests/golden/evo_real/data/.
2. Runs evo_ape / evo_rpe / evo_traj on them (CASES), in a copy of that directory, and
   records what evo printed, the stats, info and arrays of its --save_results archive, with
   `timestamps.npy` and `seconds_from_start.npy` as the integers of their float64 bits, so
   the test can ask for bit equality.
3. Writes rust/cli/tests/golden/evo_real/expected.json.

The Rust test (rust/cli/tests/evo.rs, `real_files_to_the_last_digit`) runs `sitar` with
the same arguments and compares.

Usage (from the repository root; needs `pip install evo==1.38.1` and a checkout of evo's
repository for its test/data):
    python3 scripts/golden/make_evo_real_goldens.py /path/to/evo/test/data
"""
import json
import pathlib
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from make_evo_cli_goldens import load_archive, run  # noqa: E402  (evo's archive, evo's run)

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "rust/cli/tests/golden/evo_real"
DATA = OUT / "data"
FILES = [
    "freiburg1_xyz-groundtruth.txt",
    "freiburg1_xyz-rgbdslam.txt",
    "fr2_desk_groundtruth.txt",
    "fr2_desk_ORB.txt",
    "V102_groundtruth.csv",
    "V102.txt",
]
FR1 = ["freiburg1_xyz-groundtruth.txt", "freiburg1_xyz-rgbdslam.txt"]
FR2 = ["fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"]
V102 = ["V102_groundtruth.csv", "V102.txt"]

# (name, evo tool, arguments). ape/rpe cases save their archive.
CASES = [
    # The tie at ORB stamp 1311868226.310950 and the ground truth's repeated stamp.
    ("ape_fr2_desk", "ape", ["tum", *FR2, "-a"]),
    ("rpe_fr2_desk_all_pairs", "rpe", ["tum", *FR2, "-d", "10", "--all_pairs", "-a"]),
    ("rpe_fr2_desk_metres", "rpe", ["tum", *FR2, "-d", "0.2", "-u", "m", "-r", "angle_deg"]),
    ("ape_fr2_desk_offset", "ape", ["tum", *FR2, "-a", "--t_offset", "0.0023", "--t_max_diff", "0.004"]),
    ("ape_fr2_desk_time_range", "ape", ["tum", *FR2, "-a", "-s", "--t_start", "1311868200.5", "--t_end", "1311868230.25"]),
    ("ape_fr2_desk_swapped", "ape", ["tum", FR2[1], FR2[0], "-a", "-r", "angle_deg"]),
    ("ape_fr1_xyz", "ape", ["tum", *FR1, "-a", "-s"]),
    ("rpe_fr1_xyz", "rpe", ["tum", *FR1, "-r", "angle_deg", "--all_pairs", "-d", "5"]),
    ("ape_v102_euroc", "ape", ["euroc", *V102, "-a", "-s"]),
    ("rpe_v102_euroc", "rpe", ["euroc", *V102, "-d", "1", "-u", "m", "--all_pairs"]),
    ("traj_fr2_sync", "traj", ["tum", FR2[1], "--ref", FR2[0], "--sync", "-a", "--full_check"]),
    ("traj_v102_sync", "traj", ["euroc", V102[0], "--full_check"]),
]

EXACT = ["timestamps", "seconds_from_start"]


def load_archive_exact(path):
    """evo's archive as make_evo_cli_goldens.load_archive reads it, with the EXACT arrays
    as the integers of their float64 bits (Python floats are float64, so exactly)."""
    archive = load_archive(path)
    archive["bits"] = {
        name: [int(b) for b in np.array(archive["arrays"].pop(name), dtype="<f8").view("<u8")]
        for name in EXACT
        if name in archive["arrays"]
    }
    return archive


def main():
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    source = pathlib.Path(sys.argv[1])
    DATA.mkdir(parents=True, exist_ok=True)
    for f in FILES:
        if f.endswith(".csv"):
            # evo reads the first 8 columns of a EuRoC CSV (stamp, position, w x y z); the
            # velocities and biases after them are left out to keep the repository small.
            lines = (source / f).read_text().splitlines()
            (DATA / f).write_text("".join(",".join(l.split(",")[:8]) + "\n" for l in lines))
        else:
            shutil.copy(source / f, DATA / f)
    expected = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        for name, tool, args in CASES:
            work = tmp / name
            work.mkdir()
            for f in FILES:
                shutil.copy(DATA / f, work / f)
            extra = ["--save_results", "result.zip"] if tool in ("ape", "rpe") else []
            stdout = run(tool, args + extra, work)
            case = {"name": name, "tool": tool, "args": args, "stdout": stdout, "saved": {}}
            if extra:
                case["archive"] = load_archive_exact(work / "result.zip")
            expected.append(case)
            print(f"{name}: {len(stdout.splitlines())} lines")
    (OUT / "expected.json").write_text(json.dumps(expected) + "\n")
    print(f"{len(expected)} cases")


if __name__ == "__main__":
    main()
