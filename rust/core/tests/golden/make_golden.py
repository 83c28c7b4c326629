#!/usr/bin/env python3
"""Independent reference values for sitar-core's geometry (numpy + scipy).

Writes, next to this script:
  look_rotation.csv  Unity Quaternion.LookRotation(n x (n x up), n) via scipy, Unity and ARCore.
  depth_sample.csv   5x5 depth windows (mm) -> camera/world point and normal, every
                     convention and display rotation, random poses, bumpy surfaces,
                     missing and outlying neighbours, image borders.

Run: python3 make_golden.py   (numpy, scipy; deterministic seed)
"""
import csv
import os

import numpy as np
from scipy.spatial.transform import Rotation

HERE = os.path.dirname(os.path.abspath(__file__))
rng = np.random.default_rng(20231016)


def unity_look_rotation(forward, upwards):
    """Unity's LookRotation: z = forward, x = up x z, y = z x x (columns of the matrix)."""
    z = forward / np.linalg.norm(forward)
    x = np.cross(upwards, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return Rotation.from_matrix(np.column_stack([x, y, z]))


S = np.diag([1.0, 1.0, -1.0])  # Unity <-> ARCore reflection


def canonical(q):
    q = np.asarray(q, dtype=float)
    return -q if q[3] < 0 else q


def look_rows():
    rows = []
    normals = [rng.normal(size=3) for _ in range(30)] + [np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.2, 0.0])]
    for n in normals:
        n = n / np.linalg.norm(n)
        up = np.array([0.0, 1.0, 0.0])
        if np.linalg.norm(np.cross(n, up)) < 1e-6:
            continue
        fwd = np.cross(n, np.cross(n, up))
        r_u = unity_look_rotation(fwd, n)
        q_u = canonical(r_u.as_quat())
        # Same physical rotation in ARCore coordinates: S R S.
        q_a = canonical(Rotation.from_matrix(S @ r_u.as_matrix() @ S).as_quat())
        rows.append([*n, *q_u, *(S @ n), *q_a])
    return rows


def window_normal(win, x, y, width, height, k):
    """The estimator, written independently: 5x5 window, 20 % rule, offset^2 weights."""
    fx, fy, cx, cy = k
    dc = win[2][2]
    if dc == 0:
        return None, "no_depth"
    sx = wx = sy = wy = 0.0
    for j in range(5):
        for i in range(5):
            dx, dy = i - 2, j - 2
            if dx == 0 and dy == 0:
                continue
            u, v = x + dx, y + dy
            if not (0 <= u < width and 0 <= v < height):
                continue
            d = win[j][i]
            if d == 0 or abs(d - dc) > 0.2 * dc:
                continue
            if dx:
                sx += (d - dc) * dx
                wx += dx * dx
            if dy:
                sy += (d - dc) * dy
                wy += dy * dy
    if wx == 0 or wy == 0:
        return None, "no_valid_neighbours"
    gx, gy = sx / wx / 1000.0, sy / wy / 1000.0
    z = dc / 1000.0
    ray = np.array([(x - cx) / fx, (y - cy) / fy, 1.0])
    p = z * ray
    du = gx * ray + np.array([z / fx, 0, 0])
    dv = gy * ray + np.array([0, z / fy, 0])
    n = np.cross(du, dv)
    n /= np.linalg.norm(n)
    if n @ p > 0:
        n = -n
    return (p, n), "valid"


# Optical (x right, y down, z forward) -> camera frame of each convention.
CAMERA_FROM_OPTICAL = {"unity": np.diag([1.0, -1.0, 1.0]), "arcore": np.diag([1.0, -1.0, -1.0])}


def depth_rows():
    rows = []
    width, height = 256, 192
    for case in range(60):
        k = (rng.uniform(180, 240), rng.uniform(180, 240), rng.uniform(120, 136), rng.uniform(88, 104))
        if case % 10 == 0:
            x, y = int(rng.integers(0, 2)), int(rng.integers(0, height))  # left border
        elif case % 10 == 1:
            x, y = int(rng.integers(0, width)), height - 1 - int(rng.integers(0, 2))  # bottom border
        else:
            x, y = int(rng.integers(2, width - 2)), int(rng.integers(2, height - 2))
        base = rng.uniform(500, 5000)
        slope = rng.uniform(-40, 40, size=2)
        win = [[int(round(base + slope[0] * (i - 2) + slope[1] * (j - 2) + rng.normal(0, 3)))
                for i in range(5)] for j in range(5)]
        if case % 7 == 3:
            win[int(rng.integers(0, 5))][int(rng.integers(0, 5))] = 0  # a hole
        if case % 5 == 2:
            win[int(rng.integers(0, 5))][int(rng.integers(0, 5))] = int(base * 0.5)  # an outlier
        if case == 17:
            win = [[int(base * 2)] * 5 for _ in range(5)]
            win[2][2] = int(base)  # everything rejected
        if case == 29:
            win[2][2] = 0
        win = [[min(max(d, 0), 65535) for d in row] for row in win]
        convention = "unity" if case % 2 == 0 else "arcore"
        rotation = int(90 * (case % 4))
        q = canonical(Rotation.random(random_state=int(rng.integers(0, 2**31))).as_quat())
        t = rng.uniform(-3, 3, size=3)
        got, status = window_normal(win, x, y, width, height, k)
        expect = [""] * 12
        if got is not None:
            p, n = got
            rz = Rotation.from_euler("z", rotation, degrees=True).as_matrix()  # sensor -> display
            m = CAMERA_FROM_OPTICAL[convention] @ rz
            pc, nc = m @ p, m @ n
            r = Rotation.from_quat(q).as_matrix()
            expect = [*pc, *nc, *(r @ pc + t), *(r @ nc)]
        rows.append([case, x, y, *k, convention, rotation, *t, *q,
                     " ".join(str(d) for row in win for d in row), status, *expect])
    return rows


def write(name, header, rows):
    with open(os.path.join(HERE, name), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for row in rows:
            w.writerow([repr(float(v)) if isinstance(v, (float, np.floating)) else v for v in row])


write("look_rotation.csv",
      ["nx", "ny", "nz", "qx", "qy", "qz", "qw", "anx", "any", "anz", "aqx", "aqy", "aqz", "aqw"],
      look_rows())
write("depth_sample.csv",
      ["case", "x", "y", "fx", "fy", "cx", "cy", "convention", "rotation", "tx", "ty", "tz",
       "qx", "qy", "qz", "qw", "window_mm", "status",
       "cam_x", "cam_y", "cam_z", "cam_nx", "cam_ny", "cam_nz", "x_w", "y_w", "z_w", "nx_w", "ny_w", "nz_w"],
      depth_rows())
