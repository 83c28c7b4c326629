#!/usr/bin/env python3
"""Golden outputs of evo's own command-line tools for `sitar ape|rpe|traj|res` (issue 9).

1. Writes real-format input files with the quirks real datasets have into
   rust/cli/tests/golden/evo/data/, made from the simulated walk in rust/cli/tests/golden/data
   (integer-ns TUM): TUM files in seconds; a ground truth that repeats one stamp (as the TUM
   fr2/desk ground truth does at line 10 863); an unsorted ground truth; a UTF-8 BOM; CR-only
   and CRLF line ends; quaternions of norm 1.01; an integer-second reference with a
   decimal-second estimate; a EuRoC ground-truth CSV; a KITTI pair.
2. Runs evo_ape / evo_rpe / evo_traj / evo_res on them with every flag set in CASES, in that
   directory, and records what evo printed (stdout), the stats, info and arrays of its
   --save_results archive, the files evo_traj saved, evo_res's table and --save_table.
3. Writes rust/cli/tests/golden/evo/expected.json and keeps evo's archives of the RES_SOURCES
   cases in rust/cli/tests/golden/evo/archives/ for the `res` cases.

The Rust test (rust/cli/tests/evo.rs) runs `sitar` with the same arguments, compares, and
runs evo_res on sitar's own archives when evo is installed.

Usage (from the repository root; needs `pip install evo==1.38.1`):
    python3 scripts/golden/make_evo_cli_goldens.py
"""
import json
import math
import pathlib
import shutil
import subprocess
import tempfile
import zipfile
import io

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCE = ROOT / "rust/cli/tests/golden/data"
OUT = ROOT / "rust/cli/tests/golden/evo"
DATA = OUT / "data"
ARCHIVES = OUT / "archives"


def read_ns_tum(path):
    rows = []
    for line in path.read_text().splitlines():
        t = line.split()
        if not t or t[0].startswith("#"):
            continue
        rows.append((int(t[0]), [float(v) for v in t[1:8]]))
    return rows


def seconds(ns):
    return f"{ns // 1_000_000_000}.{ns % 1_000_000_000:09d}"


def tum_lines(rows, stamp=lambda ns: seconds(ns)):
    return [" ".join([stamp(ns)] + [repr(v) for v in values]) for ns, values in rows]


def write(name, lines, newline="\n", bom=False):
    text = newline.join(lines) + newline
    data = ("\ufeff" if bom else "") + text
    (DATA / name).write_bytes(data.encode("utf-8"))


def quat_matrix(qx, qy, qz, qw):
    n = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    x, y, z, w = qx / n, qy / n, qz / n, qw / n
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def kitti_lines(rows):
    out = []
    for _, (x, y, z, qx, qy, qz, qw) in rows:
        r = quat_matrix(qx, qy, qz, qw)
        values = r[0] + [x] + r[1] + [y] + r[2] + [z]
        out.append(" ".join(repr(v) for v in values))
    return out


def make_data():
    if DATA.exists():
        shutil.rmtree(DATA)
    DATA.mkdir(parents=True)
    gt = read_ns_tum(SOURCE / "ground_truth.txt")
    est_a = read_ns_tum(SOURCE / "trials/trajectory_0.txt")
    est_b = read_ns_tum(SOURCE / "trials/trajectory_1.txt")
    write("gt.txt", ["# timestamp tx ty tz qx qy qz qw"] + tum_lines(gt))
    write("est_a.txt", tum_lines(est_a))
    write("est_b.txt", tum_lines(est_b))
    # The same walk ten seconds later: merging it with est_a orders every stamp uniquely.
    write("est_late.txt", tum_lines([(ns + 10_000_000_000, v) for ns, v in est_b]))
    # A repeated stamp with a different pose (the TUM fr2/desk ground truth's quirk).
    repeated = list(gt)
    repeated[61] = (repeated[60][0], repeated[61][1])
    write("gt_repeated.txt", tum_lines(repeated))
    # Two lines swapped: evo falls back to a linear search (and warns) for the longer one.
    unsorted = list(gt)
    unsorted[80], unsorted[81] = unsorted[81], unsorted[80]
    write("gt_unsorted.txt", tum_lines(unsorted))
    write("gt_bom.txt", tum_lines(gt), bom=True)
    write("est_cr.txt", tum_lines(est_a), newline="\r")
    write("est_crlf.txt", tum_lines(est_b), newline="\r\n")
    norm = [(ns, v[:3] + [q * 1.01 for q in v[3:]]) for ns, v in est_a]
    write("est_norm101.txt", tum_lines(norm))
    # Whole-second integer stamps for the reference, decimal seconds for the estimate.
    write("gt_int.txt", [" ".join([str(i)] + [repr(x) for x in v]) for i, (_, v) in enumerate(gt[:80])])
    est_rows = read_ns_tum(SOURCE / "trials/trajectory_2.txt")[:80]
    write("est_int_dec.txt", [" ".join([f"{i + 0.004:.3f}"] + [repr(x) for x in v]) for i, (_, v) in enumerate(est_rows)])
    # EuRoC ground truth: ns stamps, position, quaternion w x y z, then velocities.
    header = "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1]"
    csv = [header] + [
        ",".join([str(ns)] + [repr(v) for v in (x, y, z, qw, qx, qy, qz)] + ["0.0", "0.0", "0.0"])
        for ns, (x, y, z, qx, qy, qz, qw) in gt
    ]
    write("gt_euroc.csv", csv)
    # KITTI: the poses of the estimate's stamps, both files equally long.
    stamps = {ns for ns, _ in est_a}
    write("gt.kitti", kitti_lines([r for r in gt if r[0] in stamps]))
    write("est.kitti", kitti_lines(est_a))


# (name, evo tool, arguments). ape/rpe cases save their archive; traj cases may save files.
CASES = [
    ("ape_se3", "ape", ["tum", "gt.txt", "est_a.txt", "-a"]),
    ("ape_sim3", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "-s"]),
    ("ape_scale_only", "ape", ["tum", "gt.txt", "est_a.txt", "-s"]),
    ("ape_origin_full", "ape", ["tum", "gt.txt", "est_a.txt", "--align_origin", "-r", "full"]),
    ("ape_angle_deg", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "-r", "angle_deg"]),
    ("ape_angle_rad", "ape", ["tum", "gt.txt", "est_b.txt", "-a", "-r", "angle_rad"]),
    ("ape_rot_part", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "-r", "rot_part"]),
    ("ape_point_distance", "ape", ["tum", "gt.txt", "est_b.txt", "-a", "-r", "point_distance"]),
    ("ape_not_aligned", "ape", ["tum", "gt.txt", "gt.txt"]),
    ("ape_n_to_align", "ape", ["tum", "gt.txt", "est_b.txt", "-a", "--n_to_align", "50"]),
    ("ape_time_range", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "--t_start", "1001", "--t_end", "1003.5"]),
    ("ape_project_xz", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "--project_to_plane", "xz"]),
    ("ape_downsample", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "--downsample", "60"]),
    ("ape_motion_filter", "ape", ["tum", "gt.txt", "est_b.txt", "-a", "--motion_filter", "0.02", "2"]),
    ("ape_change_unit_mm", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "--change_unit", "mm"]),
    ("ape_deg_to_rad", "ape", ["tum", "gt.txt", "est_a.txt", "-a", "-r", "angle_deg", "--change_unit", "rad"]),
    ("ape_offset", "ape", ["tum", "gt.txt", "est_b.txt", "-a", "--t_offset", "0.003", "--t_max_diff", "0.02"]),
    ("ape_interpolation", "ape", ["tum", "gt.txt", "est_b.txt", "-a", "--sync_method", "interpolation"]),
    ("ape_repeated_stamp", "ape", ["tum", "gt_repeated.txt", "est_a.txt", "-a"]),
    ("ape_unsorted", "ape", ["tum", "gt_unsorted.txt", "est_b.txt", "-a"]),
    ("ape_bom_cr", "ape", ["tum", "gt_bom.txt", "est_cr.txt", "-a"]),
    ("ape_crlf", "ape", ["tum", "gt.txt", "est_crlf.txt", "-a", "-s"]),
    ("ape_norm101", "ape", ["tum", "gt.txt", "est_norm101.txt", "-a", "-r", "angle_deg"]),
    ("ape_integer_seconds", "ape", ["tum", "gt_int.txt", "est_int_dec.txt", "-a"]),
    ("ape_euroc", "ape", ["euroc", "gt_euroc.csv", "est_a.txt", "-a"]),
    ("ape_kitti", "ape", ["kitti", "gt.kitti", "est.kitti", "-a", "-r", "angle_deg"]),
    ("rpe_defaults", "rpe", ["tum", "gt.txt", "est_a.txt"]),
    ("rpe_angle_all_pairs", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "10", "--all_pairs", "-r", "angle_deg"]),
    ("rpe_metres_all_pairs", "rpe", ["tum", "gt.txt", "est_b.txt", "-d", "0.5", "-u", "m", "--all_pairs"]),
    ("rpe_metres_consecutive", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "0.25", "-u", "m"]),
    ("rpe_degrees_consecutive", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "2", "-u", "d"]),
    ("rpe_radians_all_pairs", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "0.05", "-u", "r", "--all_pairs", "-t", "0.2"]),
    ("rpe_point_distance", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "5", "-r", "point_distance"]),
    ("rpe_error_ratio", "rpe", ["tum", "gt.txt", "est_b.txt", "-d", "5", "-r", "point_distance_error_ratio", "--all_pairs"]),
    ("rpe_full_sim3", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "5", "-r", "full", "-a", "-s"]),
    ("rpe_rot_part", "rpe", ["tum", "gt.txt", "est_b.txt", "-d", "3", "-r", "rot_part"]),
    ("rpe_pairs_from_reference", "rpe", ["tum", "gt.txt", "est_b.txt", "-d", "3", "--all_pairs", "--pairs_from_reference"]),
    ("rpe_euroc", "rpe", ["euroc", "gt_euroc.csv", "est_b.txt", "-d", "10"]),
    ("rpe_kitti", "rpe", ["kitti", "gt.kitti", "est.kitti", "-d", "5", "-r", "angle_deg"]),
    ("rpe_repeated_stamp", "rpe", ["tum", "gt_repeated.txt", "est_b.txt", "-d", "10", "--all_pairs"]),
    ("rpe_project_xy", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "2", "--project_to_plane", "xy", "-r", "angle_deg"]),
    ("rpe_integer_seconds", "rpe", ["tum", "gt_int.txt", "est_int_dec.txt", "-d", "1", "-a"]),
    ("rpe_align_origin", "rpe", ["tum", "gt.txt", "est_a.txt", "-d", "4", "--align_origin", "-r", "angle_rad"]),
    ("traj_ref_align_full_check", "traj", ["tum", "est_a.txt", "est_b.txt", "--ref", "gt.txt", "-a", "--full_check"]),
    ("traj_sync_scale", "traj", ["tum", "est_a.txt", "--ref", "gt.txt", "-s", "--sync", "-v"]),
    ("traj_merge", "traj", ["tum", "est_a.txt", "est_late.txt", "--merge", "--full_check"]),
    ("traj_offset", "traj", ["tum", "est_a.txt", "--t_offset", "0.5", "-v"]),
    ("traj_euroc", "traj", ["euroc", "gt_euroc.csv", "--full_check"]),
    ("traj_kitti_ref", "traj", ["kitti", "est.kitti", "--ref", "gt.kitti", "-a", "-v"]),
    ("traj_save_tum", "traj", ["tum", "est_b.txt", "--ref", "gt.txt", "--align_origin", "--save_as_tum"]),
    ("traj_save_kitti", "traj", ["tum", "est_a.txt", "--downsample", "40", "--save_as_kitti"]),
    ("traj_repeated_stamp", "traj", ["tum", "gt_repeated.txt", "-f"]),
    ("traj_plain", "traj", ["tum", "est_a.txt", "est_b.txt", "gt.txt"]),
    ("traj_save_table", "traj", ["tum", "est_a.txt", "est_b.txt", "--save_table", "table.csv"]),
]

# res cases over evo's archives of these cases (copied to archives/NAME.zip).
RES_CASES = [
    ("res_two_estimates", ["ape_se3.zip", "ape_offset.zip"]),
    ("res_use_filenames", ["ape_se3.zip", "ape_sim3.zip", "ape_scale_only.zip", "--use_filenames"]),
    ("res_save_table", ["rpe_defaults.zip", "rpe_rot_part.zip", "--save_table", "table.csv"]),
    ("res_merge", ["ape_se3.zip", "ape_sim3.zip", "--merge"]),
    ("res_ignore_title", ["ape_se3.zip", "rpe_euroc.zip", "--ignore_title"]),
]


def load_archive(path):
    with zipfile.ZipFile(path) as z:
        arrays = {}
        for name in z.namelist():
            if name.endswith(".npy"):
                arrays[name[:-4]] = np.load(io.BytesIO(z.read(name))).tolist()
        return {
            "info": json.loads(z.read("info.json")),
            "stats": json.loads(z.read("stats.json")),
            "arrays": arrays,
            "entries": z.namelist(),
        }


def run(tool, args, cwd):
    done = subprocess.run([f"evo_{tool}", *args, "--no_warnings"], cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"evo_{tool} {' '.join(args)} failed:\n{done.stdout}{done.stderr}")
    return done.stdout


def main():
    make_data()
    if ARCHIVES.exists():
        shutil.rmtree(ARCHIVES)
    ARCHIVES.mkdir(parents=True)
    expected = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        for name, tool, args in CASES:
            work = tmp / name
            work.mkdir()
            for f in DATA.iterdir():
                shutil.copy(f, work / f.name)
            before = {p.name for p in work.iterdir()}
            extra = ["--save_results", "result.zip"] if tool in ("ape", "rpe") else []
            stdout = run(tool, args + extra, work)
            case = {"name": name, "tool": tool, "args": args, "stdout": stdout}
            if extra:
                case["archive"] = load_archive(work / "result.zip")
                shutil.copy(work / "result.zip", ARCHIVES / f"{name}.zip")
            saved = sorted({p.name for p in work.iterdir()} - before - {"result.zip"})
            case["saved"] = {f: (work / f).read_text() for f in saved}
            expected.append(case)
            print(f"{name}: {len(stdout.splitlines())} lines" + (f", saved {saved}" if saved else ""))
        for name, args in RES_CASES:
            work = tmp / name
            work.mkdir()
            for f in ARCHIVES.iterdir():
                shutil.copy(f, work / f.name)
            before = {p.name for p in work.iterdir()}
            stdout = run("res", args, work)
            saved = sorted({p.name for p in work.iterdir()} - before)
            expected.append({
                "name": name, "tool": "res", "args": args, "stdout": stdout,
                "saved": {f: (work / f).read_text() for f in saved},
            })
            print(f"{name}: {len(stdout.splitlines())} lines")
    (OUT / "expected.json").write_text(json.dumps(expected, indent=1) + "\n")
    print(f"{len(expected)} cases")


if __name__ == "__main__":
    main()
