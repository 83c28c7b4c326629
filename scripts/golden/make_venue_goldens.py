#!/usr/bin/env python3
"""Golden data for the venue map (sitar-core `venue::build_map`, issue 24).

Writes a small venue of synthetic sessions, each as the files the phone uploads, and the map
computed here independently with numpy/scipy:

  s1  unity,  world frame A, results in metres (windows jittered, some missing)
  s2  arcore, world frame B, results in metres (mirrored into the venue's unity frame)
  s3  unity,  world frame C, results in metres, walks elsewhere partly
  s4  unity,  results in degrees (angle_deg): aligned but brings no cells
  s5  unity,  the anchor only seen with limited tracking: not aligned

into rust/core/tests/golden/venue/<session>/{anchors.csv,trajectory.txt,subtrajectories.csv,
results.json} plus spec.json (the venue, the sessions' conventions) and map_min1.json /
map_min2.json (the expected map.json with min_sessions 1 and 2).

The reference follows the documented definitions, not the Rust code:
  alignment   full observations only; heading atan2(-x_z, x_x) of the image's +X; medians
              (component-wise position, circular heading), outliers beyond 3 robust sigmas
              (1.4826 MAD, floors 2 cm / 2 deg) rejected, medians of the rest, RMS spreads
  venue frame p_venue = R_y(h)^T (p_world - t), R_y(a) = [[c,0,s],[0,1,0],[-s,0,c]]
  lookup      nearest window start to the sub-trajectory's start within half the median
              frame interval (median gap of trajectory.txt stamps / 5 frames)
  heading     camera forward (unity +Z, arcore -Z) in the venue frame, counter-clockwise from
              +X seen from above: atan2(z, x) (unity) or atan2(-z, x) (arcore); sector
              floor((a + pi/8) / (pi/4)) mod 8
  cells       index floor(c / cell_m + 0.5), centre i cell_m (cells centred on multiples
              of cell_m, so the anchor's plane is mid-cell), error
              scipy.stats.trim_mean(errors, 0.3), classes 0.05 / 0.10 m
Usage: python3 scripts/golden/make_venue_goldens.py   (needs numpy, scipy)
"""
import json
import math
import pathlib
import shutil

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.stats import trim_mean

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "rust" / "core" / "tests" / "golden" / "venue"
ANCHOR = "lobby-a"
CELL_M = 0.25
VENUE_CONVENTION = "unity"
HALF = 5  # frames between logged poses (10-frame windows)
HEADER = ("index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,"
          "cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class")


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def mirror_point(p):
    return np.array([p[0], p[1], -p[2]])


def mirror_quat(q):  # xyzw, S R S
    return np.array([-q[0], -q[1], q[2], q[3]])


def wrap(a):
    t = 2 * math.pi
    w = a - t * round(a / t)
    return w + t if w <= -math.pi else w


# ---------------------------------------------------------------- the scene (venue frame, unity)

def walk(rng, n_subs, centre, radius, phase):
    """Logged camera poses (venue frame, unity numbers) every 5 frames: 2 n_subs + 1 poses."""
    poses = []
    for i in range(2 * n_subs + 1):
        a = phase + 0.045 * i
        p = np.array([centre[0] + radius * math.cos(a), 1.4 + 0.1 * math.sin(0.3 * i),
                      centre[1] + radius * math.sin(a)]) + rng.normal(0, 0.03, 3)
        yaw = rng.uniform(-math.pi, math.pi)  # unity yaw about +Y
        pitch = rng.uniform(-0.5, 0.5)
        q = Rotation.from_euler("YX", [yaw, pitch]).as_quat()  # xyzw
        poses.append((p, q))
    return poses


def to_session(poses_venue, convention, heading, translation):
    """Venue-frame unity poses into the session's world frame and convention."""
    out = []
    for p, q in poses_venue:
        if convention == "arcore":
            p, q = mirror_point(p), mirror_quat(q)
        rot = Rotation.from_quat([0, math.sin(heading / 2), 0, math.cos(heading / 2)])
        out.append((rot.apply(p) + translation, (rot * Rotation.from_quat(q)).as_quat()))
    return out


def anchor_observations(rng, convention, heading, translation, tracking_full=True):
    """The image at the venue origin on a wall (+X venue +X, tilted 90 deg about X)."""
    rows = []
    image = Rotation.from_euler("X", math.pi / 2)
    for i in range(9):
        noise_p = rng.normal(0, 0.004, 3)
        noise_h = rng.normal(0, math.radians(0.5))
        if i == 4:  # a gross outlier
            noise_p, noise_h = np.array([0.8, -0.3, 0.5]), 0.9
        q = (Rotation.from_euler("Y", noise_h) * image).as_quat()
        p = noise_p
        if convention == "arcore":
            p, q = mirror_point(p), mirror_quat(q)
        rot = Rotation.from_quat([0, math.sin(heading / 2), 0, math.cos(heading / 2)])
        wp = rot.apply(p) + translation
        wq = (rot * Rotation.from_quat(q)).as_quat()
        tracking = "full" if tracking_full else "limited"
        if i in (2, 7):
            tracking = "limited"
            wp = wp + np.array([3.0, 0.0, -2.0])
        rows.append((1_000 + 33_000_000 * i, wp, wq, tracking))
    return rows


# ---------------------------------------------------------------- files

def write_session(folder, rng, poses, stamps, convention, relation, window_drop):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "trajectory.txt").write_text("".join(
        f"{t} {float(p[0])!r} {float(p[1])!r} {float(p[2])!r} {float(q[0])!r} {float(q[1])!r} {float(q[2])!r} {float(q[3])!r}\n"
        for t, (p, q) in zip(stamps, poses)))
    fwd_local = np.array([0.0, 0.0, 1.0 if convention == "unity" else -1.0])
    lines = [HEADER if relation == "trans_part" else HEADER.replace(",error_m,", ",error_deg,")]
    n_subs = (len(poses) - 1) // 2
    for k in range(n_subs):
        start, mid, end = stamps[2 * k], stamps[2 * k + 1], stamps[2 * k + 2]
        p, q = poses[2 * k + 1]
        if k % 7 == 3:
            lines.append(f"{k},{start},{mid},{end},no_depth,128,96" + "," * 14 + ",,")
            continue
        d = rng.uniform(0.8, 3.0)
        f = Rotation.from_quat(q).apply(fwd_local)
        s = p + d * f
        n = -f
        lines.append(f"{k},{start},{mid},{end},valid,128,96,{float(d)!r},{float(d)!r},0,0,{float(d)!r},0,0,-1,"
                     f"{float(s[0])!r},{float(s[1])!r},{float(s[2])!r},{float(n[0])!r},{float(n[1])!r},{float(n[2])!r},,")
    (folder / "subtrajectories.csv").write_text("\n".join(lines) + "\n")
    # Windows at every frame, starts jittered by up to a third of a frame, some dropped.
    frame_stamps = []
    for i in range(len(stamps) - 1):
        for j in range(HALF):
            frame_stamps.append(stamps[i] + (stamps[i + 1] - stamps[i]) * j // HALF)
    windows = []
    key = "error_m" if relation == "trans_part" else "error_deg"
    for i, t in enumerate(frame_stamps):
        if i in window_drop:
            continue
        jitter = int(rng.integers(-11_000_000, 11_000_000))
        err = float(rng.choice([rng.uniform(0.0, 0.04), rng.uniform(0.04, 0.2)]))
        windows.append({"start": t + jitter, "end": t + jitter + 333_000_000, key: err,
                        "pairs": 28})
    doc = {"version": 1, "setting": "trim_mean_30", "trials": 8, "window_frames": 10,
           "pose_relation": relation, "unit": "m" if relation == "trans_part" else "deg",
           "windows": windows}
    (folder / "results.json").write_text(json.dumps(doc))


def write_anchors(folder, rows):
    lines = ["t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking"]
    for t, p, q, tracking in rows:
        lines.append(f"{t},{ANCHOR},{float(p[0])!r},{float(p[1])!r},{float(p[2])!r},{float(q[0])!r},{float(q[1])!r},{float(q[2])!r},"
                     f"{float(q[3])!r},{tracking}")
    (folder / "anchors.csv").write_text("\n".join(lines) + "\n")


# ---------------------------------------------------------------- the reference computation

def read_anchors(folder):
    rows = []
    for line in (folder / "anchors.csv").read_text().splitlines()[1:]:
        c = line.split(",")
        rows.append((np.array([float(v) for v in c[2:5]]), np.array([float(v) for v in c[5:9]]),
                     c[9], c[1]))
    return rows


def reference_alignment(folder):
    full = []
    for p, q, tracking, anchor in read_anchors(folder):
        if tracking != "full" or anchor != ANCHOR:
            continue
        x = Rotation.from_quat(q).apply([1.0, 0.0, 0.0])
        full.append((p, math.atan2(-x[2], x[0])))
    if not full:
        return None

    def centre(obs):
        ps = np.array([o[0] for o in obs])
        hs = np.array([o[1] for o in obs])
        ref = math.atan2(np.sin(hs).sum(), np.cos(hs).sum())
        dev = np.array([wrap(h - ref) for h in hs])
        return np.median(ps, axis=0), wrap(ref + float(np.median(dev)))

    p0, h0 = centre(full)
    r = np.array([np.linalg.norm(p - p0) for p, _ in full])
    a = np.array([abs(wrap(h - h0)) for _, h in full])
    pos_limit = max(3.0 * 1.4826 * float(np.median(r)), 0.02)
    ang_limit = max(3.0 * 1.4826 * float(np.median(a)), math.radians(2.0))
    used = [(p, h) for p, h in full
            if np.linalg.norm(p - p0) <= pos_limit and abs(wrap(h - h0)) <= ang_limit] or full
    t, h = centre(used)
    pos_spread = math.sqrt(np.mean([np.sum((p - t) ** 2) for p, _ in used]))
    head_spread = math.degrees(math.sqrt(np.mean([wrap(x - h) ** 2 for _, x in used])))
    return {"translation": t, "heading": h, "observations": len(used),
            "position_spread_m": pos_spread, "heading_spread_deg": head_spread}


def reference_samples(folder, convention, alignment):
    poses = {}
    stamps = []
    for line in (folder / "trajectory.txt").read_text().splitlines():
        v = line.split()
        poses[int(v[0])] = (np.array([float(x) for x in v[1:4]]),
                            np.array([float(x) for x in v[4:8]]))
        stamps.append(int(v[0]))
    gaps = sorted(b - a for a, b in zip(stamps, stamps[1:]))
    m = len(gaps) // 2
    median2 = 2 * gaps[m] if len(gaps) % 2 else gaps[m - 1] + gaps[m]
    tolerance = median2 // (4 * HALF)
    results = json.loads((folder / "results.json").read_text())
    windows = sorted(((w["start"], w["error_m"]) for w in results["windows"]),
                     key=lambda w: w[0])
    starts = np.array([w[0] for w in windows])
    r_inv = ry(alignment["heading"]).T
    t = alignment["translation"]
    fwd_local = np.array([0.0, 0.0, 1.0 if convention == "unity" else -1.0])
    samples = []
    for line in (folder / "subtrajectories.csv").read_text().splitlines()[1:]:
        c = line.split(",")
        start, mid = int(c[1]), int(c[2])
        dist = np.abs(starts - start)
        best = int(np.argmin(dist))  # first of equals: the earlier start
        if dist[best] > tolerance:
            continue
        error = windows[best][1]
        p, q = poses[mid]
        position = r_inv @ (p - t)
        forward = r_inv @ Rotation.from_quat(q).apply(fwd_local)
        north = forward[2] if convention == "unity" else -forward[2]
        heading = math.atan2(north, forward[0])
        sector = int(np.floor((heading + np.pi / 8) / (np.pi / 4))) % 8
        surface = None
        if c[4] == "valid":
            surface = r_inv @ (np.array([float(x) for x in c[15:18]]) - t)
        if convention != VENUE_CONVENTION:
            position = mirror_point(position)
            surface = None if surface is None else mirror_point(surface)
        samples.append((position, surface, error, sector))
    return samples


def reference_map(sessions, min_sessions):
    cells = {}
    listing = []
    for name, convention, folder, state in sessions:
        if state["kind"] != "in_map":
            listing.append({"id": name, "aligned": False, "reason": state["reason"]})
            continue
        a = state["alignment"]
        samples = reference_samples(folder, convention, a)
        listing.append({"id": name, "aligned": True, "observations": a["observations"],
                        "position_spread_m": a["position_spread_m"],
                        "heading_spread_deg": a["heading_spread_deg"],
                        "subtrajectories": len(samples)})
        for position, surface, error, sector in samples:
            for kind, point in ((0, position), (1, surface)):
                if point is None:
                    continue
                key = (kind,) + tuple(int(v) for v in np.floor(point / CELL_M + 0.5))
                cells.setdefault(key, []).append((name, error, sector))
    out = []
    for key in sorted(cells):
        members = cells[key]
        n_sessions = len({m[0] for m in members})
        if n_sessions < min_sessions:
            continue
        error = float(trim_mean(np.array([m[1] for m in members]), 0.3))
        directions = [0] * 8
        for m in members:
            directions[m[2]] += 1
        out.append({"center": [i * CELL_M for i in key[1:]],
                    "kind": "path" if key[0] == 0 else "surface",
                    "sessions": n_sessions, "subtrajectories": len(members),
                    "error_m": error,
                    "class": "high" if error >= 0.10 else "medium" if error >= 0.05 else "low",
                    "directions": directions})
    return {"id": "v00000000000000a1", "name": "Golden lobby", "anchor": ANCHOR,
            "cell_m": CELL_M, "convention": VENUE_CONVENTION, "unit": "m",
            "sessions": listing, "cells": out}


def main():
    rng = np.random.default_rng(24)
    if OUT.exists():
        shutil.rmtree(OUT)
    specs = [  # name, convention, heading, translation, relation, centre, radius, phase
        ("s1", "unity", 0.7, np.array([2.0, -0.3, 1.5]), "trans_part", (0.0, 2.0), 1.2, 0.0),
        ("s2", "arcore", -2.4, np.array([-4.0, 0.2, 7.0]), "trans_part", (0.0, 2.0), 1.2, 0.4),
        ("s3", "unity", 2.9, np.array([0.5, 0.0, -3.0]), "trans_part", (0.6, 2.4), 1.0, 1.0),
        ("s4", "unity", 1.1, np.array([1.0, 0.0, 1.0]), "angle_deg", (0.0, 2.0), 1.2, 0.2),
        ("s5", "unity", 0.0, np.array([0.0, 0.0, 0.0]), "trans_part", (0.0, 2.0), 1.2, 0.0),
    ]
    sessions = []
    for name, convention, heading, translation, relation, centre, radius, phase in specs:
        folder = OUT / name
        n_subs = 60
        venue_poses = walk(rng, n_subs, centre, radius, phase)
        poses = to_session(venue_poses, convention, heading, translation)
        t0 = 1_700_000_000_000_000_000 + 10**9 * len(sessions)
        stamps = [t0]
        for _ in range(2 * n_subs):
            stamps.append(stamps[-1] + 5 * 33_333_333 + int(rng.integers(-900_000, 900_000)))
        drop = set(int(i) for i in rng.choice(5 * 2 * n_subs, 40, replace=False))
        write_session(folder, rng, poses, stamps, convention, relation, drop)
        write_anchors(folder, anchor_observations(rng, convention, heading, translation,
                                                  tracking_full=(name != "s5")))
        alignment = reference_alignment(folder)
        if alignment is None:
            state = {"kind": "not_aligned",
                     "reason": f"the anchor `{ANCHOR}` was observed 9 times but never with "
                               "full tracking"}
        elif relation != "trans_part":
            state = {"kind": "excluded",
                     "reason": "its results are angle_deg (errors in deg); the map's cells "
                               "are in metres (trans_part)"}
        else:
            state = {"kind": "in_map", "alignment": alignment}
            err = np.linalg.norm(alignment["translation"] - translation)
            assert err < 0.01 and abs(wrap(alignment["heading"] - heading)) < 0.02, name
        sessions.append((name, convention, folder, state))
    (OUT / "spec.json").write_text(json.dumps({
        "id": "v00000000000000a1", "name": "Golden lobby", "anchor": ANCHOR, "cell_m": CELL_M,
        "convention": VENUE_CONVENTION,
        "sessions": [{"id": s[0], "convention": s[1]} for s in sessions]}, indent=1))
    for min_sessions in (1, 2):
        m = reference_map(sessions, min_sessions)
        (OUT / f"map_min{min_sessions}.json").write_text(json.dumps(m, indent=1))
        print(f"min_sessions {min_sessions}: {len(m['cells'])} cells, "
              f"{sum(c['sessions'] >= 2 for c in m['cells'])} seen by 2+ sessions, "
              f"{sum(c['class'] == 'high' for c in m['cells'])} high")


if __name__ == "__main__":
    main()
