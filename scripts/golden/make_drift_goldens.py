#!/usr/bin/env python3
"""Golden data for sitar-estimator's `drift` (the KITTI odometry benchmark's metric), from an
independent numpy implementation of the KITTI devkit's formulas (evaluate_odometry.cpp), not
from sitar.

Writes into rust/estimator/tests/data/:
  drift/kitti_gt.txt, drift/kitti_est.txt  a synthetic KITTI-format pair (400 poses, about
                          919 m at 10 Hz, 19-27 m/s): the estimate integrates the ground
                          truth's frame-to-frame motion with a scale error of 1.5 %, a yaw
                          drift of 0.005 deg per metre and a little noise
  golden_drift.json       per case: the options, every segment (kitti) or its first/last
                          poses (real run), the mean over all segments, per length, per speed

Cases:
  kitti_synthetic         the pair above, the devkit's defaults (100..800 m, a start every 10
                          poses, speed from 10 Hz frames, speed bins 2..24 m/s +- 2)
  euroc_mh04_run0         ../shared/data/real-runs/euroc-vio/MH_04: ground_truth.txt vs
                          runs/run0.txt (TUM), paired by stamps as evo's
                          associate_trajectories (the shorter trajectory walked, the nearest
                          stamp within 0.01 s), lengths 1..8 m (indoors), speed from the
                          ground truth's stamps
  euroc_mh04_run0_speed_0.2  the same with speed bins 0.2, 0.4, .. 2.4 m/s (+- 0.2)

The devkit's formulas, as implemented here with 4x4 matrices:
  dist[i]     cumulative ground-truth path length
  last        first i >= first with dist[i] > dist[first] + L (lastFrameFromSegmentLength)
  error pose  inv(inv(E_first) E_last) . (inv(G_first) G_last)   (the devkit's own order)
  t_err       |translation of the error pose| / L  (x 100: %)
  r_err       rotation angle of the error pose / L (degrees per metre; the devkit: rad/m)
  speed       L / (0.1 (last - first + 1)) for frames, L / (t_last - t_first) for stamps
The angle is the devkit's acos((trace - 1) / 2), computed as atan2(|vee(R - R^T)| / 2,
(trace - 1) / 2): the same angle, without acos' loss of digits near 0 (the golden is compared
to 1e-9 relative; the largest difference of the two forms is printed).

Usage: python3 scripts/golden/make_drift_goldens.py   (needs numpy, scipy)
"""
import json
import pathlib

import numpy as np
from scipy.spatial.transform import Rotation

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "rust" / "estimator" / "tests" / "data"
REAL = ROOT.parent / "shared" / "data" / "real-runs" / "euroc-vio" / "MH_04"
SEED = 20240717
N = 400
SCALE = 1.015
YAW_DRIFT_DEG_PER_M = 0.005


def to_matrix(rotation, translation):
    m = np.eye(4)
    m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def synthetic_pair():
    """KITTI camera frames (x right, y down, z forward): a drive with turns and hills."""
    rng = np.random.default_rng(SEED)
    k = np.arange(N - 1)
    step = 2.3 + 0.4 * np.sin(2 * np.pi * k / 97.0)  # metres per frame: 19..27 m/s
    yaw_rate = 0.012 * np.sin(2 * np.pi * k / 150.0)  # rad per frame
    pitch = 0.02 * np.sin(2 * np.pi * np.arange(N) / 230.0)
    yaw = np.concatenate([[0.0], np.cumsum(yaw_rate)])
    gt = [np.eye(4)]
    for i in range(N - 1):
        r = Rotation.from_euler("YX", [yaw[i], pitch[i]]).as_matrix()
        p = gt[-1][:3, 3] + r @ np.array([0.0, 0.0, step[i]])
        r_next = Rotation.from_euler("YX", [yaw[i + 1], pitch[i + 1]]).as_matrix()
        gt.append(to_matrix(r_next, p))
    est = [np.eye(4)]
    for i in range(N - 1):
        rel = np.linalg.inv(gt[i]) @ gt[i + 1]
        length = np.linalg.norm(rel[:3, 3])
        drift = Rotation.from_euler("Y", np.radians(YAW_DRIFT_DEG_PER_M) * length)
        noise = Rotation.from_rotvec(rng.normal(scale=2e-4, size=3))
        rotation = (drift * noise).as_matrix() @ rel[:3, :3]
        translation = SCALE * rel[:3, 3] + rng.normal(scale=0.01, size=3)
        est.append(est[-1] @ to_matrix(rotation, translation))
    return gt, est


def write_kitti(path, poses):
    with open(path, "w") as f:
        for m in poses:
            f.write(" ".join(repr(float(v)) for v in m[:3, :4].reshape(-1)) + "\n")


def read_kitti(path):
    rows = np.loadtxt(path).reshape(-1, 3, 4)
    return [np.vstack([r, [0.0, 0.0, 0.0, 1.0]]) for r in rows]


def read_tum(path):
    data = np.loadtxt(path, comments="#")
    poses = [
        to_matrix(Rotation.from_quat(row[4:8]).as_matrix(), row[1:4]) for row in data
    ]
    return data[:, 0], poses


def associate(stamps_ref, stamps_est, max_diff=0.01):
    """evo's associate_trajectories: walk the shorter trajectory (the second on a tie), take
    the nearest stamp of the other (the first on a tie) within max_diff."""
    est_longer = len(stamps_est) > len(stamps_ref)
    short, long_ = (stamps_ref, stamps_est) if est_longer else (stamps_est, stamps_ref)
    ids_short, ids_long = [], []
    for i, t in enumerate(short):
        diffs = np.abs(long_ - t)
        j = int(np.argmin(diffs))
        if diffs[j] <= max_diff:
            ids_short.append(i)
            ids_long.append(j)
    return (ids_short, ids_long) if est_longer else (ids_long, ids_short)


def angle(r):
    vee = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return np.arctan2(np.linalg.norm(vee) / 2.0, (np.trace(r) - 1.0) / 2.0)


def devkit_angle(r):
    return np.arccos(max(min(0.5 * (np.trace(r) - 1.0), 1.0), -1.0))


def drift(gt, est, lengths, step, durations, speed_bins, half_width):
    positions = np.array([m[:3, 3] for m in gt])
    dist = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(positions, axis=0), axis=1))])
    segments = []
    worst_acos = 0.0
    for first in range(0, len(gt), step):
        for length in lengths:
            beyond = np.nonzero(dist[first:] > dist[first] + length)[0]
            if len(beyond) == 0:
                continue
            last = first + int(beyond[0])
            delta_gt = np.linalg.inv(gt[first]) @ gt[last]
            delta_est = np.linalg.inv(est[first]) @ est[last]
            error = np.linalg.inv(delta_est) @ delta_gt
            theta = angle(error[:3, :3])
            if theta > 1e-6:
                worst_acos = max(worst_acos, abs(devkit_angle(error[:3, :3]) - theta) / theta)
            segments.append(
                {
                    "first": first,
                    "last": last,
                    "length_m": float(length),
                    "speed_m_s": float(length / durations(first, last)),
                    "t_err_percent": float(100.0 * np.linalg.norm(error[:3, 3]) / length),
                    "r_err_deg_per_m": float(np.degrees(theta) / length),
                }
            )
    print(f"  {len(segments)} segments; acos vs atan2 angle: {worst_acos:.2e} relative at most")

    def mean_of(chosen):
        return {
            "segments": len(chosen),
            "t_err_percent": float(np.mean([s["t_err_percent"] for s in chosen])),
            "r_err_deg_per_m": float(np.mean([s["r_err_deg_per_m"] for s in chosen])),
        }

    by_length = []
    for length in lengths:
        chosen = [s for s in segments if s["length_m"] == length]
        if len(chosen) >= 3:
            by_length.append({"length_m": float(length), **mean_of(chosen)})
    by_speed = []
    for centre in speed_bins:
        chosen = [s for s in segments if abs(s["speed_m_s"] - centre) < half_width]
        if len(chosen) >= 3:
            by_speed.append({"speed_m_s": float(centre), **mean_of(chosen)})
    overall = mean_of(segments)
    return {
        "t_err_percent": overall["t_err_percent"],
        "r_err_deg_per_m": overall["r_err_deg_per_m"],
        "segments": overall["segments"],
        "by_length": by_length,
        "by_speed": by_speed,
        "segment_list": segments,
    }


def speed_bins(step):
    return [k * step for k in range(1, 13)]


def main():
    (OUT / "drift").mkdir(parents=True, exist_ok=True)
    gt, est = synthetic_pair()
    write_kitti(OUT / "drift" / "kitti_gt.txt", gt)
    write_kitti(OUT / "drift" / "kitti_est.txt", est)
    cases = []

    print("kitti_synthetic")
    gt, est = read_kitti(OUT / "drift" / "kitti_gt.txt"), read_kitti(OUT / "drift" / "kitti_est.txt")
    lengths = [100.0 * k for k in range(1, 9)]
    result = drift(gt, est, lengths, 10, lambda a, b: 0.1 * (b - a + 1), speed_bins(2.0), 2.0)
    cases.append(
        {
            "name": "kitti_synthetic",
            "format": "kitti",
            "reference": "drift/kitti_gt.txt",
            "estimate": "drift/kitti_est.txt",
            "lengths_m": lengths,
            "step": 10,
            "duration": "frames",
            "interval_s": 0.1,
            "speed_step_m_s": 2.0,
            "scale_error": SCALE,
            "yaw_drift_deg_per_m": YAW_DRIFT_DEG_PER_M,
            **result,
        }
    )

    stamps_gt, gt = read_tum(REAL / "ground_truth.txt")
    stamps_run, run = read_tum(REAL / "runs" / "run0.txt")
    ids_gt, ids_run = associate(stamps_gt, stamps_run)
    gt = [gt[i] for i in ids_gt]
    run = [run[i] for i in ids_run]
    t = stamps_gt[ids_gt]
    print(f"euroc: {len(ids_gt)} of {len(stamps_run)} run poses associated")
    lengths = [float(k) for k in range(1, 9)]
    for name, step in [("euroc_mh04_run0", 2.0), ("euroc_mh04_run0_speed_0.2", 0.2)]:
        print(name)
        result = drift(gt, run, lengths, 10, lambda a, b: t[b] - t[a], speed_bins(step), step)
        # Only the segments' poses for the real run, once (the errors are checked via the
        # means).
        if step == 2.0:
            result["segment_list"] = [[s["first"], s["last"]] for s in result["segment_list"]]
        else:
            del result["segment_list"]
        cases.append(
            {
                "name": name,
                "format": "tum",
                "reference": "real-runs/euroc-vio/MH_04/ground_truth.txt",
                "estimate": "real-runs/euroc-vio/MH_04/runs/run0.txt",
                "associated_poses": len(ids_gt),
                "lengths_m": lengths,
                "step": 10,
                "duration": "stamps",
                "speed_step_m_s": step,
                **result,
            }
        )
    with open(OUT / "golden_drift.json", "w") as f:
        json.dump(cases, f, indent=1)
        f.write("\n")
    for c in cases:
        print(
            f"{c['name']}: {c['segments']} segments, t_err {c['t_err_percent']:.4f} %, "
            f"r_err {c['r_err_deg_per_m']:.6f} deg/m, {len(c['by_length'])} lengths, "
            f"{len(c['by_speed'])} speed bins"
        )


if __name__ == "__main__":
    main()
