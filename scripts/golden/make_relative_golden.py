#!/usr/bin/env python3
"""Golden data for sitar-estimator's relative error at sub-trajectory lengths and rpg's
pairing and alignment (rpg_trajectory_evaluation, Zhang & Scaramuzza IROS 2018), from an
independent numpy implementation of that toolbox's definitions, not from sitar nor rpg's code.

Writes into rust/estimator/tests/data/:
  relative/synthetic_gt.txt, relative/synthetic_est.txt  a TUM pair (600 poses at 20 Hz,
                          a 2 s stop in the middle, stamps 3-6 ms apart, every 50th ground
                          truth pose missing): the estimate is the ground truth in another
                          frame (yaw 40 deg, shifted), scaled by 0.8, with a slow yaw and roll
                          drift and a little noise
  golden_relative.json    per case: the files, the alignment, the transform, the APE
                          translation RMSE, and per length the number of sub-trajectories,
                          statistics of each error and every 37th sample

Definitions (rpg's):
  pairing     every (estimate, ground truth) pair of stamps closer than 0.02 s, taken by
              increasing difference, each pose once (TUM associate.py), sorted by estimate
  alignment   gt = s R est + t on the first n poses (-1: all): sim3 / se3 Umeyama, posyaw the
              least-squares yaw about z; n = 1: se3 the first pose, posyaw the first yaw
  APE         |p_gt - (s R p_est + t)|, RMSE
  lengths     percentages p of the whole ground-truth file's path: trunc(p/100 * len, 2 dp)
  D           cumulative path of the *paired* ground truth
  end of i    argmin_j>=i |D_j - (D_i + L)| (earliest on ties) if that is < 0.2 L
  error       E = inv(inv(G_i) G_j) (inv(Est_i) Est_j) with the estimate's translation x s,
              E_w = R_est_j E R_est_j^T; trans |t|, % = 100 |t| / L, rot acos((tr-1)/2) deg,
              deg/m = rot / L, yaw |atan2(R10, R00)|, roll-pitch sqrt(pitch^2 + roll^2)
  fewer than 2 sub-trajectories at a length: none

Usage: python3 scripts/golden/make_relative_golden.py   (needs numpy)
"""
import json
import os
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "rust/estimator/tests/data"
REAL = ROOT.parent / "shared/data/real-runs/euroc-vio"
METRICS = ["trans_m", "trans_percent", "rot_deg", "rot_deg_per_m", "yaw_deg", "roll_pitch_deg"]


def load_tum(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    a = np.array([[float(v) for v in r] for r in rows])
    return a[:, 0], a[:, 1:4], a[:, 4:8]


def rotation(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def pair(t_est, t_gt, max_diff=0.02):
    # Stamps in integer nanoseconds, as the Rust side keeps them.
    a = np.round(t_est * 1e9).astype(np.int64)
    b = np.round(t_gt * 1e9).astype(np.int64)
    limit = int(round(max_diff * 1e9))
    cand = []
    for i, s in enumerate(a):
        for j in np.nonzero(np.abs(b - s) < limit)[0]:
            cand.append((abs(int(s) - int(b[j])), i, int(j)))
    cand.sort()
    used_a, used_b, out = set(), set(), []
    for _, i, j in cand:
        if i not in used_a and j not in used_b:
            used_a.add(i)
            used_b.add(j)
            out.append((i, j))
    return sorted(out)


def umeyama(est, gt, with_scale):
    mx, my = est.mean(0), gt.mean(0)
    x, y = est - mx, gt - my
    cov = y.T @ x / len(est)
    u, d, vt = np.linalg.svd(cov)
    s = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s[2, 2] = -1
    r = u @ s @ vt
    c = np.trace(np.diag(d) @ s) / (x * x).sum(1).mean() if with_scale else 1.0
    return c, r, my - c * r @ mx


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def align(kind, n, p_est, p_gt, q_est, q_gt):
    if kind == "none":
        return 1.0, np.eye(3), np.zeros(3)
    n = len(p_est) if n == -1 else n
    if n == 1 and kind == "se3":
        r = rotation(q_gt[0]) @ rotation(q_est[0]).T
        return 1.0, r, p_gt[0] - r @ p_est[0]
    if n == 1 and kind == "posyaw":
        # The yaw that brings the estimate's first heading onto the ground truth's: the
        # rotation about z nearest (Frobenius) to R_gt R_est^T.
        m = rotation(q_gt[0]) @ rotation(q_est[0]).T
        r = rot_z(np.arctan2(m[1, 0] - m[0, 1], m[0, 0] + m[1, 1]))
        return 1.0, r, p_gt[0] - r @ p_est[0]
    x, y = p_est[:n], p_gt[:n]
    if kind == "posyaw":
        x0, y0 = x - x.mean(0), y - y.mean(0)
        sin = np.sum(x0[:, 0] * y0[:, 1] - x0[:, 1] * y0[:, 0])
        cos = np.sum(x0[:, 0] * y0[:, 0] + x0[:, 1] * y0[:, 1])
        r = rot_z(np.arctan2(sin, cos))
        return 1.0, r, y.mean(0) - r @ x.mean(0)
    return umeyama(x, y, kind == "sim3")


def relative(p_gt, q_gt, p_est, q_est, scale, length):
    d = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p_gt, axis=0), axis=1))))
    ends = []
    for i in range(len(d)):
        err = np.abs(d[i:] - (d[i] + length))
        k = int(np.argmin(err))  # the first minimum: the earliest on ties
        if err[k] < 0.2 * length:
            ends.append((i, i + k))
    if len(ends) < 2:
        return []
    r_gt = [rotation(q) for q in q_gt]
    r_est = [rotation(q) for q in q_est]
    out = []
    for i, j in ends:
        g = np.eye(4)
        g[:3, :3] = r_gt[i].T @ r_gt[j]
        g[:3, 3] = r_gt[i].T @ (p_gt[j] - p_gt[i])
        e = np.eye(4)
        e[:3, :3] = r_est[i].T @ r_est[j]
        e[:3, 3] = scale * r_est[i].T @ (p_est[j] - p_est[i])
        err = np.linalg.inv(g) @ e
        w = np.eye(4)
        w[:3, :3] = r_est[j]
        ew = w @ err @ w.T
        r = ew[:3, :3]
        tn = np.linalg.norm(ew[:3, 3])
        rot = np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1)))
        yaw = np.arctan2(r[1, 0], r[0, 0])
        pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
        roll = np.arctan2(r[2, 1], r[2, 2])
        out.append({
            "start": i, "end": j, "trans_m": tn, "trans_percent": tn / length * 100,
            "rot_deg": rot, "rot_deg_per_m": rot / length, "yaw_deg": abs(np.degrees(yaw)),
            "roll_pitch_deg": np.degrees(np.hypot(pitch, roll)),
        })
    return out


def stats(v):
    v = np.asarray(v)
    return {"rmse": float(np.sqrt(np.mean(v * v))), "mean": float(np.mean(v)),
            "median": float(np.median(v)), "std": float(np.std(v)),
            "min": float(np.min(v)), "max": float(np.max(v))}


def case(name, gt_file, est_file, kind, n, lengths=None, percents=None):
    t_gt, p_gt_all, q_gt_all = load_tum(gt_file)
    t_est, p_est_all, q_est_all = load_tum(est_file)
    pairs = pair(t_est, t_gt)
    ie = [i for i, _ in pairs]
    ig = [j for _, j in pairs]
    p_est, q_est = p_est_all[ie], q_est_all[ie]
    p_gt, q_gt = p_gt_all[ig], q_gt_all[ig]
    s, r, t = align(kind, n, p_est, p_gt, q_est, q_gt)
    ape = np.linalg.norm(p_gt - (s * (r @ p_est.T).T + t), axis=1)
    path = float(np.cumsum(np.linalg.norm(np.diff(p_gt_all, axis=0), axis=1))[-1])
    if lengths is None:
        lengths = [np.trunc(p / 100 * path * 100) / 100 for p in percents]
    per_length = []
    for length in lengths:
        samples = relative(p_gt, q_gt, p_est, q_est, s, length)
        per_length.append({
            "length_m": length,
            "count": len(samples),
            "stats": {m: stats([x[m] for x in samples]) for m in METRICS} if samples else None,
            "samples": samples[::37],
        })
    rel = lambda p: os.path.relpath(pathlib.Path(p).resolve(), ROOT)
    return {
        "name": name, "reference": rel(gt_file), "estimate": rel(est_file),
        "align_type": kind, "align_num_frames": n, "percents": percents,
        "pairs": len(pairs), "first_pairs": pairs[:5], "path_length_m": path,
        "scale": float(s), "rotation": r.tolist(), "translation": t.tolist(),
        "ape_rmse_m": float(np.sqrt(np.mean(ape * ape))), "lengths": per_length,
    }


def quat(r):
    # Shepperd's method, (x, y, z, w).
    tr = np.trace(r)
    if tr > 0:
        w = np.sqrt(1 + tr) / 2
        return np.array([(r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w),
                         (r[1, 0] - r[0, 1]) / (4 * w), w])
    i = int(np.argmax(np.diag(r)))
    j, k = (i + 1) % 3, (i + 2) % 3
    v = np.zeros(4)
    v[i] = np.sqrt(1 + r[i, i] - r[j, j] - r[k, k]) / 2
    v[j] = (r[j, i] + r[i, j]) / (4 * v[i])
    v[k] = (r[k, i] + r[i, k]) / (4 * v[i])
    v[3] = (r[k, j] - r[j, k]) / (4 * v[i])
    return v


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def write_synthetic():
    rng = np.random.default_rng(34)
    n = 600
    t = 1_400_000_000.0 + np.arange(n) * 0.05
    u = np.arange(n) * 0.05
    moving = np.clip(u, 0, 12) + np.clip(u - 14, 0, None)  # stopped from 12 s to 14 s
    p = np.stack([3 * np.cos(0.3 * moving), 2 * np.sin(0.45 * moving), 1 + 0.2 * np.sin(moving)], 1)
    r = [rot_z(0.3 * m + 0.5) @ rot_x(0.1 * np.sin(m)) for m in moving]
    d = REL / "synthetic_gt.txt"
    e = REL / "synthetic_est.txt"
    frame = rot_z(np.radians(40))
    shift = np.array([5.0, -1.0, 0.3])
    with open(d, "w") as f:
        f.write("# timestamp tx ty tz qx qy qz qw\n")
        for k in range(n):
            if k % 50 == 7:
                continue
            f.write(" ".join(f"{v:.9f}" for v in [t[k], *p[k], *quat(r[k])]) + "\n")
    with open(e, "w") as f:
        for k in range(n):
            drift = rot_z(np.radians(0.02 * k)) @ rot_x(np.radians(0.01 * k))
            pk = 0.8 * (frame @ (p[k] + rng.normal(0, 0.01, 3))) + shift
            rk = frame @ drift @ r[k]
            stamp = t[k] + rng.uniform(0.003, 0.006)
            f.write(" ".join(f"{v:.9f}" for v in [stamp, *pk, *quat(rk)]) + "\n")
    return d, e


REL = OUT / "relative"


def main():
    REL.mkdir(parents=True, exist_ok=True)
    gt, est = write_synthetic()
    cases = [
        case("synthetic_sim3", gt, est, "sim3", -1, percents=[10, 20, 30, 40, 50]),
        case("synthetic_se3_first", gt, est, "se3", 1, lengths=[1.0, 2.5, 4.0, 60.0]),
        case("synthetic_se3_50", gt, est, "se3", 50, lengths=[2.0]),
        case("synthetic_posyaw_first", gt, est, "posyaw", 1, lengths=[3.0]),
        case("synthetic_none", gt, est, "none", -1, lengths=[0.5, 3.0]),
    ]
    for seq in ["MH_04", "MH_05", "V1_02"]:
        for run in [0, 7]:
            cases.append(case(f"{seq}_run{run}_posyaw", REAL / seq / "ground_truth.txt",
                              REAL / seq / "runs" / f"run{run}.txt", "posyaw", -1,
                              percents=[10, 20, 30, 40, 50]))
    cases.append(case("MH_04_run3_sim3_lengths", REAL / "MH_04/ground_truth.txt",
                      REAL / "MH_04/runs/run3.txt", "sim3", 100, lengths=[8.0, 16.0, 24.0]))
    path = OUT / "golden_relative.json"
    path.write_text(json.dumps({"generator": "scripts/golden/make_relative_golden.py",
                                "cases": cases}, indent=1) + "\n")
    for c in cases:
        print(c["name"], c["pairs"], "pairs, APE", round(c["ape_rmse_m"], 4),
              [(l["length_m"], l["count"]) for l in c["lengths"]])


if __name__ == "__main__":
    main()
