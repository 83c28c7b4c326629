"""Fixtures: the real EuRoC runs (skipped with the reason when absent), a small synthetic
TUM pair, and the CLI to compare with (``SITAR_BIN``, else the installed ``sitar``)."""

import json
import math
import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
REAL_RUNS = REPO.parent / "shared" / "data" / "real-runs" / "euroc-vio"


@pytest.fixture(scope="session")
def mh04():
    """(ground truth, [run0, run1, run2]) of MH_04, or a skip naming the missing folder."""
    seq = REAL_RUNS / "MH_04"
    runs = [seq / "runs" / f"run{k}.txt" for k in range(3)]
    if not (seq / "ground_truth.txt").is_file() or not all(r.is_file() for r in runs):
        pytest.skip(f"SKIPPED: the real runs are missing ({seq})")
    return seq / "ground_truth.txt", runs


@pytest.fixture(scope="session")
def synthetic(tmp_path_factory):
    """A TUM reference (a circle, 200 poses at 10 Hz) and a noisy, offset estimate."""
    folder = tmp_path_factory.mktemp("synthetic")
    ref, est = folder / "ref.txt", folder / "est.txt"
    with open(ref, "w") as r, open(est, "w") as e:
        for i in range(200):
            t = 100.0 + 0.1 * i
            a = 0.05 * i
            x, y, z = 2 * math.cos(a), 2 * math.sin(a), 0.1 * math.sin(3 * a)
            qz, qw = math.sin(a / 2), math.cos(a / 2)
            r.write(f"{t:.6f} {x:.9f} {y:.9f} {z:.9f} 0 0 {qz:.9f} {qw:.9f}\n")
            n = 0.01 * math.sin(7.3 * i)
            e.write(f"{t:.6f} {x + 1 + n:.9f} {y - 0.5:.9f} {z + n:.9f} 0 0 {qz:.9f} {qw:.9f}\n")
    return ref, est


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI with ``--format json`` and returns the parsed document."""
    binary = os.environ.get("SITAR_BIN") or shutil.which("sitar")
    if not binary:
        pytest.skip("SKIPPED: no sitar CLI (set SITAR_BIN or install the package)")

    def run(*args):
        out = subprocess.run(
            [binary, *map(str, args), "--format", "json"],
            check=True,
            capture_output=True,
            text=True,
        )
        return json.loads(out.stdout)

    return run


REAL = REPO.parent / "shared" / "data" / "real-runs"


@pytest.fixture(scope="session")
def real_runs(tmp_path_factory):
    """(name, reader, ref, est) of the real runs with ground truth: EuRoC MH_04 and TUM
    fr1_desk (TUM files), and KITTI 00 written as KITTI pose files (its TUM runs associated
    with evo and written with evo's writer). Empty when the data is absent (the tests then
    run on the synthetic files only)."""
    out = []
    for name, seq in (("MH_04", REAL / "euroc-vio" / "MH_04"),
                      ("fr1_desk", REAL / "tum-orbslam2-rgbd" / "fr1_desk")):
        if (seq / "ground_truth.txt").is_file() and (seq / "runs" / "run0.txt").is_file():
            out.append((name, "read_tum_trajectory_file", seq / "ground_truth.txt",
                        seq / "runs" / "run0.txt"))
    kitti = REAL / "kitti-orbslam2-stereo" / "00"
    if (kitti / "ground_truth.txt").is_file() and (kitti / "runs" / "run0.txt").is_file():
        from evo.core import sync
        from evo.tools import file_interface

        folder = tmp_path_factory.mktemp("kitti")
        ref, est = sync.associate_trajectories(
            file_interface.read_tum_trajectory_file(str(kitti / "ground_truth.txt")),
            file_interface.read_tum_trajectory_file(str(kitti / "runs" / "run0.txt")),
        )
        file_interface.write_kitti_poses_file(str(folder / "gt.kitti"), ref)
        file_interface.write_kitti_poses_file(str(folder / "run0.kitti"), est)
        out.append(("KITTI 00", "read_kitti_poses_file", folder / "gt.kitti", folder / "run0.kitti"))
    if not out:
        print(f"SKIPPED the real runs: missing ({REAL})")
    return out
