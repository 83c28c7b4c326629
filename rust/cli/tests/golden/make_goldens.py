#!/usr/bin/env python3
"""Golden results for `sitar rpe` / `sitar ape`, made with evo's own command-line tools.

The inputs are files written by `sitar simulate` (integer-nanosecond TUM, own world frame
per trial, dropped frames) plus one trial written in decimal seconds. evo reads TUM stamps as
seconds, so it gets second-unit copies; sitar reads the originals. Every case passes the SAME
evo-style arguments to `evo_rpe tum` / `evo_ape tum` and to `sitar rpe` / `sitar ape`.

Usage (from the repository root; needs `pip install evo numpy`):
    python3 rust/cli/tests/golden/make_goldens.py [--sitar target/debug/sitar]
With --sitar the input data is regenerated first; otherwise the committed data is used.
Writes rust/cli/tests/golden/expected.json.
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import tempfile

from evo.tools import file_interface

HERE = pathlib.Path(__file__).resolve().parent
DATA = HERE / "data"

# (name, tool, reference, estimate, evo-style arguments)
CASES = [
    ("rpe_trans_f10", "rpe", "ground_truth.txt", "trials/trajectory_0.txt",
     ["-r", "trans_part", "--delta", "10", "--delta_unit", "f"]),
    ("rpe_trans_f10_all_pairs_dropped", "rpe", "ground_truth.txt", "trials/trajectory_1.txt",
     ["-r", "trans_part", "--delta", "10", "--delta_unit", "f", "--all_pairs"]),
    ("rpe_angle_deg_f5_all_pairs", "rpe", "trials/trajectory_0.txt", "trials/trajectory_2.txt",
     ["-r", "angle_deg", "--delta", "5", "--delta_unit", "f", "--all_pairs"]),
    ("rpe_angle_rad_f3", "rpe", "ground_truth.txt", "trials/trajectory_2.txt",
     ["-r", "angle_rad", "--delta", "3", "--delta_unit", "f"]),
    ("rpe_trans_m05_all_pairs", "rpe", "ground_truth.txt", "trials/trajectory_0.txt",
     ["-r", "trans_part", "--delta", "0.5", "--delta_unit", "m", "--all_pairs"]),
    ("rpe_full_sim3", "rpe", "ground_truth.txt", "trials/trajectory_1.txt",
     ["-r", "full", "--delta", "10", "--delta_unit", "f", "-a", "-s"]),
    ("rpe_trans_seconds_vs_ns", "rpe", "ground_truth.txt", "trial_seconds.txt",
     ["-r", "trans_part", "--delta", "10", "--delta_unit", "f", "--all_pairs"]),
    ("ape_trans_se3", "ape", "ground_truth.txt", "trials/trajectory_0.txt",
     ["-r", "trans_part", "-a"]),
    ("ape_trans_sim3_dropped", "ape", "ground_truth.txt", "trials/trajectory_1.txt",
     ["-r", "trans_part", "-a", "-s"]),
    ("ape_trans_scale_only", "ape", "ground_truth.txt", "trials/trajectory_2.txt",
     ["-r", "trans_part", "-s"]),
    ("ape_angle_deg_se3", "ape", "ground_truth.txt", "trials/trajectory_2.txt",
     ["-r", "angle_deg", "-a"]),
    ("ape_full_origin", "ape", "ground_truth.txt", "trials/trajectory_0.txt",
     ["-r", "full", "--align_origin"]),
    ("ape_trans_none", "ape", "trials/trajectory_0.txt", "trials/trajectory_0.txt",
     ["-r", "trans_part"]),
    ("ape_trans_seconds_vs_ns_offset", "ape", "ground_truth.txt", "trial_seconds.txt",
     ["-r", "trans_part", "-a", "--t_offset", "0.001", "--t_max_diff", "0.005"]),
]


def regenerate(sitar):
    if DATA.exists():
        shutil.rmtree(DATA)
    run = lambda *a: subprocess.run([sitar, "simulate", *a], check=True)
    run("--out", str(DATA), "--trials", "3", "--seconds", "5", "--seed", "7",
        "--drop-frames", "0.05")
    with tempfile.TemporaryDirectory() as tmp:
        run("--out", tmp, "--trials", "4", "--seconds", "5", "--seed", "7", "--time-unit", "s")
        shutil.copy(pathlib.Path(tmp) / "trials" / "trajectory_3.txt", DATA / "trial_seconds.txt")
    for extra in ("scene.json", "recording.sitarsim"):
        (DATA / extra).unlink()


def seconds_copy(src, dst):
    """evo reads the first column as seconds: convert integer-ns files."""
    lines = []
    for line in src.read_text().splitlines():
        tokens = line.split()
        if tokens and not tokens[0].startswith("#") and "." not in tokens[0] and "e" not in tokens[0]:
            ns = int(tokens[0])
            tokens[0] = f"{ns // 1_000_000_000}.{ns % 1_000_000_000:09d}"
        lines.append(" ".join(tokens))
    dst.write_text("\n".join(lines) + "\n")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sitar", help="sitar binary: regenerate the input data first")
    args = parser.parse_args()
    if args.sitar:
        regenerate(args.sitar)
    expected = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        for name, tool, ref, est, evo_args in CASES:
            ref_s, est_s = tmp / f"{name}_ref.txt", tmp / f"{name}_est.txt"
            seconds_copy(DATA / ref, ref_s)
            seconds_copy(DATA / est, est_s)
            zip_path = tmp / f"{name}.zip"
            subprocess.run([f"evo_{tool}", "tum", str(ref_s), str(est_s), *evo_args,
                            "--save_results", str(zip_path), "--no_warnings", "--silent"],
                           check=True)
            result = file_interface.load_res_file(str(zip_path))
            expected.append({
                "name": name,
                "tool": tool,
                "reference": ref,
                "estimate": est,
                "args": evo_args,
                "errors": [float(e) for e in result.np_arrays["error_array"]],
                # evo's result stamps: APE per pose, RPE the end pose of each pair (seconds).
                "stamps_s": [float(t) for t in result.np_arrays["timestamps"]],
                "stats": {k: float(v) for k, v in result.stats.items()},
            })
            print(f"{name}: {len(expected[-1]['errors'])} errors, rmse {result.stats['rmse']:.6g}")
    (HERE / "expected.json").write_text(json.dumps(expected, indent=1) + "\n")


if __name__ == "__main__":
    main()
