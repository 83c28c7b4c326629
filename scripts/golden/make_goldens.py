#!/usr/bin/env python3
"""Generate golden reference data for sitar-estimator with evo, numpy and scipy.

Deterministic (fixed seed). Writes into rust/estimator/tests/data/:
  gt.txt                  ground truth (integer-ns TUM)
  trials/trial_NN.txt     SLAM-like trials: each in its own world frame, with drift that grows
                          in a "hard" stretch, some with dropped frames, one with stamp jitter
                          (some frames beyond max_diff), one written in decimal seconds
  golden_rpe.json         evo RPE on associated pairs for several options
  golden_ape.json         evo APE with every alignment mode and pose relation
  golden_estimate.json    SiTAR pairwise estimate for every setting (evo RPE + scipy/numpy)
  trials/shared_nearest_00.txt  trial_00 with a few stamps moved so that two of its frames
                          share one nearest stamp: associated trajectories repeat a stamp
  golden_estimate_shared_nearest.json  the estimate over trials that include it

Usage: python3 scripts/golden/make_goldens.py   (needs: pip install evo numpy scipy)
"""
import copy
import json
import pathlib

import numpy as np
import scipy.stats
from scipy.spatial.transform import Rotation

from evo.core import metrics, sync
from evo.core.metrics import PoseRelation, Unit
from evo.core.trajectory import PoseTrajectory3D

OUT = pathlib.Path(__file__).resolve().parents[2] / "rust" / "estimator" / "tests" / "data"
SEED = 20231016
FPS = 30.0
FRAMES = 450  # 15 s at 30 fps
T0_NS = 12_345_678_901_234
MAX_DIFF = 0.01
DELTA = 10
rng = np.random.default_rng(SEED)


def ground_truth():
    k = np.arange(FRAMES)
    stamps = T0_NS + np.round(k * 1e9 / FPS).astype(np.int64)
    t = k / FPS
    pos = np.stack([1.5 * np.sin(0.4 * t), 0.3 * np.sin(0.9 * t) + 1.4, 1.2 * np.cos(0.3 * t) + 0.05 * t], axis=1)
    yaw = 0.6 * np.sin(0.25 * t)
    pitch = 0.15 * np.sin(0.7 * t)
    roll = 0.05 * np.cos(1.1 * t)
    rot = Rotation.from_euler("yxz", np.stack([yaw, pitch, roll], axis=1))
    return stamps, pos, rot


def make_trial(index, stamps, pos, rot):
    hard = (np.arange(FRAMES) >= 180) & (np.arange(FRAMES) < 260)
    sigma_t = np.where(hard, 0.004 + 0.001 * index, 0.0004)
    sigma_r = np.where(hard, 0.003, 0.0002)
    drift_t = np.cumsum(rng.normal(size=(FRAMES, 3)) * sigma_t[:, None], axis=0)
    drift_r = Rotation.from_rotvec(np.cumsum(rng.normal(size=(FRAMES, 3)) * sigma_r[:, None], axis=0))
    if index == 4:  # a heavy-tailed outlier: a jump inside the hard stretch
        drift_t[220:] += np.array([0.12, -0.05, 0.08])
    est_rot = drift_r * rot
    est_pos = drift_r.apply(pos) + drift_t
    if index == 7:  # a scale error, as monocular SLAM would have
        est_pos = est_pos * 1.07
    # Each trial has its own world frame.
    world_rot = Rotation.from_rotvec(rng.normal(size=3) * 0.8)
    world_t = rng.normal(size=3) * 2.0
    est_pos = world_rot.apply(est_pos) + world_t
    est_rot = world_rot * est_rot
    trial_stamps = stamps.copy()
    keep = np.ones(FRAMES, dtype=bool)
    if index in (2, 5):  # dropped frames
        keep[rng.choice(np.arange(1, FRAMES - 1), size=6 if index == 2 else 14, replace=False)] = False
    if index == 3:  # stamp jitter within max_diff, a few frames beyond it
        jitter = rng.integers(-4_000_000, 4_000_001, size=FRAMES)
        jitter[[50, 51, 300]] = [12_500_000, -13_000_000, 11_000_000]
        trial_stamps = trial_stamps + jitter
    return trial_stamps[keep], est_pos[keep], est_rot[keep]


def fmt(v):
    return repr(float(v))


def write_tum(path, stamps, pos, rot, seconds=False):
    quat = rot.as_quat()  # x y z w
    lines = ["# timestamp tx ty tz qx qy qz qw\n"]
    for s, p, q in zip(stamps, pos, quat):
        s = int(s)
        st = f"{s // 1_000_000_000}.{s % 1_000_000_000:09d}" if seconds else str(s)
        lines.append(" ".join([st] + [fmt(v) for v in p] + [fmt(v) for v in q]) + "\n")
    path.write_text("".join(lines))


def write_euroc(path, stamps, pos, rot):
    """EuRoC ground-truth CSV: ns stamp, position, quaternion w x y z, then velocity columns."""
    quat = rot.as_quat()
    lines = ["#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_x, v_y, v_z\n"]
    for s, p, q in zip(stamps, pos, quat):
        fields = [str(int(s))] + [fmt(v) for v in p] + [fmt(q[3]), fmt(q[0]), fmt(q[1]), fmt(q[2])] + ["0", "0", "0"]
        lines.append(",".join(fields) + "\n")
    path.write_text("".join(lines))


def write_kitti(path, pos, rot):
    """KITTI poses: the row-major 3x4 [R | t] per line."""
    lines = []
    for p, m in zip(pos, rot.as_matrix()):
        lines.append(" ".join(fmt(v) for v in np.hstack([m, p[:, None]]).ravel()) + "\n")
    path.write_text("".join(lines))


def read_tum(path):
    """Reads our TUM files back (ns or seconds) into (stamps_ns, evo trajectory)."""
    stamps, rows = [], []
    for line in path.read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        tok = line.split()
        if "." in tok[0]:
            whole, frac = tok[0].split(".")
            stamps.append(int(whole) * 1_000_000_000 + int(frac.ljust(9, "0")))
        else:
            stamps.append(int(tok[0]))
        rows.append([float(v) for v in tok[1:]])
    rows = np.array(rows)
    stamps = np.array(stamps, dtype=np.int64)
    traj = PoseTrajectory3D(
        positions_xyz=rows[:, 0:3],
        orientations_quat_wxyz=rows[:, [6, 3, 4, 5]],
        timestamps=stamps / 1e9,
    )
    return stamps, traj


def ns_of(stamps_ns, traj_full, traj_reduced):
    lookup = {float(t): int(ns) for t, ns in zip(traj_full.timestamps, stamps_ns)}
    return [lookup[float(t)] for t in traj_reduced.timestamps]


def stats(errors):
    e = np.asarray(errors)
    return {
        "rmse": float(np.sqrt(np.mean(e**2))),
        "mean": float(np.mean(e)),
        "median": float(np.median(e)),
        "std": float(np.std(e)),
        "min": float(np.min(e)),
        "max": float(np.max(e)),
        "sse": float(np.sum(e**2)),
    }


RELATIONS = {
    "trans": PoseRelation.translation_part,
    "angle_deg": PoseRelation.rotation_angle_deg,
    "angle_rad": PoseRelation.rotation_angle_rad,
    "full": PoseRelation.full_transformation,
}


def golden_rpe(files):
    cases = []
    pairs = [("trial_00.txt", "trial_03.txt"), ("trial_02.txt", "trial_05.txt"), ("gt.txt", "trial_06.txt")]
    options = [
        dict(delta=10, unit="f", all_pairs=True),
        dict(delta=1, unit="f", all_pairs=False),
        dict(delta=25, unit="f", all_pairs=False),
        dict(delta=0.5, unit="m", all_pairs=True),
        dict(delta=0.5, unit="m", all_pairs=False),
    ]
    cases_by_pair = [(r, e, 0.0, options) for r, e in pairs]
    # A time offset of the second trajectory (evo's offset_2), shifting which frames match.
    cases_by_pair.append(("trial_00.txt", "trial_03.txt", -0.0333, options[:1]))
    # Two frames of the walked trajectory share their nearest stamp: evo keeps both matches.
    cases_by_pair.append(("gt.txt", "shared_nearest_00.txt", 0.0, options[:2]))
    for ref_name, est_name, offset, pair_options in cases_by_pair:
        _, ref = files[ref_name]
        _, est = files[est_name]
        ref_s, est_s = sync.associate_trajectories(ref, est, max_diff=MAX_DIFF, offset_2=offset)
        for opt in pair_options:
            for rel_name, rel in RELATIONS.items():
                unit = Unit.frames if opt["unit"] == "f" else Unit.meters
                rpe = metrics.RPE(rel, delta=opt["delta"], delta_unit=unit, all_pairs=opt["all_pairs"])
                rpe.process_data((ref_s, est_s))
                cases.append({
                    "reference": ref_name, "estimate": est_name, "t_max_diff": MAX_DIFF, "t_offset": offset,
                    "delta": opt["delta"], "delta_unit": opt["unit"], "all_pairs": opt["all_pairs"],
                    "pose_relation": rel_name, "align": "none",
                    "end_ids": [int(j) for j in rpe.delta_ids],
                    "errors": [float(v) for v in rpe.error], "stats": stats(rpe.error),
                })
    return cases


def golden_ape(files):
    cases = []
    _, gt = files["gt.txt"]
    for est_name in ["trial_01.txt", "trial_03.txt", "trial_05.txt", "trial_06.txt", "trial_07.txt", "mirror_01.txt",
                     "shared_nearest_00.txt"]:
        _, est = files[est_name]
        for align in ["none", "se3", "sim3", "scale", "origin"]:
            ref_s, est_s = sync.associate_trajectories(gt, est, max_diff=MAX_DIFF)
            est_a = copy.deepcopy(est_s)
            if align == "se3":
                est_a.align(ref_s)
            elif align == "sim3":
                est_a.align(ref_s, correct_scale=True)
            elif align == "scale":
                est_a.align(ref_s, correct_only_scale=True)
            elif align == "origin":
                est_a.align_origin(ref_s)
            for rel_name, rel in RELATIONS.items():
                ape = metrics.APE(rel)
                ape.process_data((ref_s, est_a))
                cases.append({
                    "reference": "gt.txt", "estimate": est_name, "t_max_diff": MAX_DIFF,
                    "align": align, "pose_relation": rel_name,
                    "errors": [float(v) for v in ape.error], "stats": stats(ape.error),
                })
    return cases


def mean_inliers(v):
    q1, q3 = np.percentile(v, [25, 75])
    iqr = q3 - q1
    keep = v[(v >= q1 - 1.5 * iqr) & (v <= q3 + 1.5 * iqr)]
    return float(np.mean(keep))


SETTINGS = {
    "mean": lambda v: float(np.mean(v)),
    "median": lambda v: float(np.median(v)),
    "trim_mean_10": lambda v: float(scipy.stats.trim_mean(v, 0.1)),
    "trim_mean_20": lambda v: float(scipy.stats.trim_mean(v, 0.2)),
    "trim_mean_30": lambda v: float(scipy.stats.trim_mean(v, 0.3)),
    "trim_mean_40": lambda v: float(scipy.stats.trim_mean(v, 0.4)),
    "mean_inliers": mean_inliers,
}


def golden_estimate(files, trial_names, relation_name):
    """ARCHITECTURE.md "Pairwise estimation": trial i is the reference of every pair i < j."""
    buckets = {}
    relation = RELATIONS[relation_name]
    for i in range(len(trial_names)):
        for j in range(i + 1, len(trial_names)):
            ns_i, traj_i = files[trial_names[i]]
            _, traj_j = files[trial_names[j]]
            ref_s, est_s = sync.associate_trajectories(traj_i, traj_j, max_diff=MAX_DIFF)
            rpe = metrics.RPE(relation, delta=DELTA, delta_unit=Unit.frames, all_pairs=True)
            rpe.process_data((ref_s, est_s))
            keys = ns_of(ns_i, traj_i, ref_s)
            # With all_pairs and a frame delta, pair k starts at index k.
            assert [int(j) for j in rpe.delta_ids] == list(range(DELTA, DELTA + len(rpe.error)))
            for k, value in enumerate(rpe.error):
                buckets.setdefault(keys[k], []).append(float(value))
    result = {}
    for name, fn in SETTINGS.items():
        rows = []
        for key in sorted(buckets):
            v = np.array(buckets[key])
            rows.append([key, fn(v), len(v), float(np.std(v))])
        result[name] = rows
    return {"trials": trial_names, "delta": DELTA, "t_max_diff": MAX_DIFF,
            "pose_relation": relation_name, "settings": result}


def main():
    (OUT / "trials").mkdir(parents=True, exist_ok=True)
    stamps, pos, rot = ground_truth()
    write_tum(OUT / "gt.txt", stamps, pos, rot)
    trial_names = []
    for index in range(8):
        s, p, r = make_trial(index, stamps, pos, rot)
        name = f"trial_{index:02d}.txt"
        write_tum(OUT / "trials" / name, s, p, r, seconds=(index == 6))
        trial_names.append(name)
    write_euroc(OUT / "gt_euroc.csv", stamps, pos, rot)
    write_kitti(OUT / "gt_kitti.txt", pos, rot)
    # One more trial, mirrored (x -> -x; drawn after the others so they stay unchanged):
    # Umeyama must not return the reflection.
    s1, p1, r1 = make_trial(1, stamps, pos, rot)
    write_tum(OUT / "trials" / "mirror_01.txt", s1, p1 * np.array([-1.0, 1.0, 1.0]), r1)
    # trial_00 with stamps moved by -24, -28 and +24 ms (no random draws, so the files above
    # stay as they are): each moved frame lands within MAX_DIFF of a neighbour's stamp.
    files = {"gt.txt": read_tum(OUT / "gt.txt")}
    for name in trial_names + ["mirror_01.txt"]:
        files[name] = read_tum(OUT / "trials" / name)
    ns0, traj0 = files["trial_00.txt"]
    shared = ns0.copy()
    shared[[100, 300]] -= [24_000_000, 28_000_000]
    shared[200] += 24_000_000
    write_tum(OUT / "trials" / "shared_nearest_00.txt", shared, traj0.positions_xyz,
              Rotation.from_quat(traj0.orientations_quat_wxyz[:, [1, 2, 3, 0]]))
    files["shared_nearest_00.txt"] = read_tum(OUT / "trials" / "shared_nearest_00.txt")
    dump = lambda name, obj: (OUT / name).write_text(json.dumps(obj, separators=(",", ":")) + "\n")
    dump("golden_rpe.json", golden_rpe(files))
    dump("golden_ape.json", golden_ape(files))
    dump("golden_estimate.json", golden_estimate(files, trial_names, "trans"))
    dump("golden_estimate_angle_deg.json", golden_estimate(files, trial_names, "angle_deg"))
    shared_names = ["trial_00.txt", "trial_01.txt", "shared_nearest_00.txt", "trial_02.txt"]
    dump("golden_estimate_shared_nearest.json", golden_estimate(files, shared_names, "trans"))


if __name__ == "__main__":
    main()
