#!/usr/bin/env python3
"""Golden data for sitar-estimator's APE by direction (`direction_components`: along-track,
cross-track, vertical, yaw and roll/pitch), from an independent numpy/scipy implementation of
the definitions in rust/estimator/src/direction.rs, not from sitar.

Writes into rust/estimator/tests/data/:
  direction/est.txt         an estimate of tests/data/gt.txt (TUM, same stamps): the ground
                            truth's positions plus a slow drift and noise (a few cm), its
                            orientations turned by a world-frame yaw drift (up to ~10 deg)
                            and a small tilt (~1 deg) with noise
  golden_direction.json     per gravity axis ("z", "y"): the signed along_track, cross_track,
                            vertical (m), yaw_deg and roll_pitch_deg at every pose

Definitions (at pose i; e = p_est - p_ref; g = +z or +y):
  heading h   p_ref[i+1] - p_ref[i-1] (forward/backward difference at the ends), its
              horizontal part (minus its component along g), normalised; where that is zero
              the nearest pose's heading, earlier first
  along       e . h,   cross   e . (g x h),   vertical   e . g
  R           R_est R_ref^T (world frame)
  roll_pitch  the swing's angle, computed here as the angle between g and R g
              (atan2(|g x Rg|, g . Rg)): a swing about a horizontal axis moves g by its angle,
              the twist about g does not move it
  yaw         R = swing . twist, twist = swing^-1 R with swing the minimal rotation taking g
              to R g; yaw = the twist's rotation vector . g, in degrees
Both are computed differently from the Rust code (which splits the quaternion), so the test
checks the definitions, not a transcription.

Usage: python3 scripts/golden/make_direction_goldens.py   (needs numpy, scipy)
"""
import json
import pathlib

import numpy as np
from scipy.spatial.transform import Rotation

DATA = pathlib.Path(__file__).resolve().parents[2] / "rust/estimator/tests/data"


def read_tum(path):
    rows = [
        line.split()
        for line in path.read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    stamps = [r[0] for r in rows]
    values = np.array([[float(x) for x in r[1:]] for r in rows])
    return stamps, values[:, :3], Rotation.from_quat(values[:, 3:7])


def make_estimate():
    stamps, p, rot = read_tum(DATA / "gt.txt")
    n = len(stamps)
    rng = np.random.default_rng(20261206)
    s = np.linspace(0.0, 1.0, n)
    drift = np.stack([0.05 * s, -0.03 * s**2, 0.02 * np.sin(3 * s)], axis=1)
    p_est = p + drift + rng.normal(0.0, 0.01, size=(n, 3))
    yaw = np.radians(10.0) * s + rng.normal(0.0, np.radians(0.2), size=n)
    tilt = np.stack([np.full(n, np.radians(1.0)), np.radians(0.5) * s, np.zeros(n)], axis=1)
    noise = rng.normal(0.0, np.radians(0.1), size=(n, 3))
    world_error = (
        Rotation.from_rotvec(np.stack([np.zeros(n), np.zeros(n), yaw], axis=1))
        * Rotation.from_rotvec(tilt + noise)
    )
    r_est = world_error * rot
    q = r_est.as_quat()
    out = DATA / "direction"
    out.mkdir(exist_ok=True)
    lines = ["# timestamp tx ty tz qx qy qz qw"]
    for i in range(n):
        values = list(p_est[i]) + list(q[i])
        lines.append(" ".join([stamps[i]] + [repr(float(v)) for v in values]))
    (out / "est.txt").write_text("\n".join(lines) + "\n")


def headings(p, g):
    n = len(p)
    raw = []
    for i in range(n):
        a, b = max(i - 1, 0), min(i + 1, n - 1)
        d = p[b] - p[a]
        horizontal = d - np.dot(d, g) * g
        length = np.linalg.norm(horizontal)
        raw.append(horizontal / length if length > 0 else None)
    out = []
    for i in range(n):
        if raw[i] is not None:
            out.append(raw[i])
            continue
        for k in range(1, n):
            if i - k >= 0 and raw[i - k] is not None:
                out.append(raw[i - k])
                break
            if i + k < n and raw[i + k] is not None:
                out.append(raw[i + k])
                break
    return np.array(out)


def minimal_rotation(a, b):
    """The smallest rotation taking unit vector a to unit vector b."""
    axis = np.cross(a, b)
    s = np.linalg.norm(axis)
    angle = np.arctan2(s, np.dot(a, b))
    if s == 0:
        return Rotation.identity()
    return Rotation.from_rotvec(axis / s * angle)


def components(p_ref, r_ref, p_est, r_est, g):
    h = headings(p_ref, g)
    e = p_est - p_ref
    left = np.cross(g, h)
    out = {"along_track": [], "cross_track": [], "vertical": [], "yaw_deg": [], "roll_pitch_deg": []}
    for i in range(len(p_ref)):
        out["along_track"].append(float(np.dot(e[i], h[i])))
        out["cross_track"].append(float(np.dot(e[i], left[i])))
        out["vertical"].append(float(np.dot(e[i], g)))
        r = r_est[i] * r_ref[i].inv()
        rg = r.apply(g)
        roll_pitch = np.arctan2(np.linalg.norm(np.cross(g, rg)), np.dot(g, rg))
        swing = minimal_rotation(g, rg)
        twist = swing.inv() * r
        yaw = float(np.dot(twist.as_rotvec(), g))
        out["yaw_deg"].append(float(np.degrees(yaw)))
        out["roll_pitch_deg"].append(float(np.degrees(roll_pitch)))
    return out


def main():
    make_estimate()
    _, p_ref, r_ref = read_tum(DATA / "gt.txt")
    _, p_est, r_est = read_tum(DATA / "direction/est.txt")
    golden = {
        "reference": "gt.txt",
        "estimate": "direction/est.txt",
        "z": components(p_ref, r_ref, p_est, r_est, np.array([0.0, 0.0, 1.0])),
        "y": components(p_ref, r_ref, p_est, r_est, np.array([0.0, 1.0, 0.0])),
    }
    (DATA / "golden_direction.json").write_text(json.dumps(golden, indent=1) + "\n")
    z = golden["z"]
    print(
        "poses", len(z["yaw_deg"]),
        "max |yaw| deg", max(map(abs, z["yaw_deg"])),
        "max roll_pitch deg", max(z["roll_pitch_deg"]),
    )


if __name__ == "__main__":
    main()
