#!/usr/bin/env python3
"""One calibration in plain Python: the reference `naocalib batch` is timed against.

    python3 scripts/solve_scipy.py DATASET

Reads dataset.toml ([camera] only; default board and robot), captures.csv and corners.csv,
fits the paper's 21 offsets with scipy.optimize.least_squares (trust region, numerical
Jacobian, the model vectorised over captures with numpy) and prints them in report units
with the whole process's wall time. No distortion, no uncertainty: a lower bound of what a
Python tool costs per dataset.

Needs `pip install numpy scipy`.
"""

import csv
import os
import sys
import time

START = time.perf_counter()

import numpy as np  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

try:
    import tomllib
except ImportError:  # Python < 3.11
    tomllib = None

NAMES = (
    "CamYaw CamPitch CamRoll "
    "LHipYawPitch LHipRoll LHipPitch LKneePitch LAnklePitch LAnkleRoll "
    "RHipYawPitch RHipRoll RHipPitch RKneePitch RAnklePitch RAnkleRoll "
    "LBoardRotZ LBoardTransX LBoardTransY RBoardRotZ RBoardTransX RBoardTransY"
).split()
LEG = "HipYawPitch HipRoll HipPitch KneePitch AnklePitch AnkleRoll".split()


def rot(axis, a):
    """Batched 4×4 rotations about a local axis by angles `a` (shape N)."""
    n = a.shape[0]
    c, s = np.cos(a), np.sin(a)
    m = np.zeros((n, 4, 4))
    m[:, 3, 3] = 1.0
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    k = 3 - i - j
    m[:, k, k] = 1.0
    m[:, i, i] = c
    m[:, j, j] = c
    m[:, i, j] = -s
    m[:, j, i] = s
    return m


def trans(x, y, z, n):
    m = np.tile(np.eye(4), (n, 1, 1))
    m[:, 0, 3], m[:, 1, 3], m[:, 2, 3] = x, y, z
    return m


def chain(*ms):
    out = ms[0]
    for m in ms[1:]:
        out = out @ m
    return out


def main():
    d = sys.argv[1]
    cam = {"fx": 562.5, "fy": 562.5, "cx": 324.0, "cy": 189.0}
    if tomllib:
        with open(os.path.join(d, "dataset.toml"), "rb") as f:
            cam.update(tomllib.load(f).get("camera", {}))
    with open(os.path.join(d, "captures.csv"), newline="") as f:
        caps = {int(r["capture"]): r for r in csv.DictReader(f)}
    rows = []
    with open(os.path.join(d, "corners.csv"), newline="") as f:
        for r in csv.DictReader(f):
            rows.append((int(r["capture"]), int(r["row"]), int(r["col"]), float(r["u"]), float(r["v"])))
    cap = np.array([r[0] for r in rows])
    uv = np.array([[r[3], r[4]] for r in rows])
    pb = np.array([[(r[2] - 2.5) * 25.0, (r[1] - 1.5) * 25.0, 0.0, 1.0] for r in rows])
    ids = sorted(caps)
    index = {c: i for i, c in enumerate(ids)}
    ci = np.array([index[c] for c in cap])
    joints = lambda name: np.array([float(caps[c][name]) for c in ids])  # noqa: E731
    left = np.array([caps[c]["board"] == "left" for c in ids])
    s = np.where(left, 1.0, -1.0)
    head_yaw, head_pitch = joints("HeadYaw"), joints("HeadPitch")
    leg = {j: np.where(left, joints("L" + j), joints("R" + j)) for j in LEG}
    n = len(ids)
    zero = np.zeros(n)
    t_head = chain(trans(0, 0, 211.5, n), rot("z", head_yaw), rot("y", head_pitch),
                   trans(50.71, 0, 17.74, n), rot("y", zero + 0.69289571))

    def residuals(a):
        t_oc = chain(t_head, rot("y", zero + a[1]), rot("x", zero + a[2]), rot("z", zero + a[0]))
        off = np.where(left[:, None], a[3:9][None, :], a[9:15][None, :])
        q = {j: leg[j] + off[:, k] for k, j in enumerate(LEG)}
        board = np.where(left[:, None], a[15:18][None, :], a[18:21][None, :])
        t_os = chain(
            trans(0, s * 50.0, 0, n), rot("x", s * np.pi / 4), rot("z", -s * q["HipYawPitch"]),
            rot("x", -s * np.pi / 4), rot("x", q["HipRoll"]), rot("y", q["HipPitch"]),
            trans(0, 0, -100.0, n), rot("y", q["KneePitch"]), trans(0, 0, -102.9, n),
            rot("y", q["AnklePitch"]), rot("x", q["AnkleRoll"]), trans(0, 0, -45.19, n),
            rot("z", board[:, 0]), trans(board[:, 1], board[:, 2], 0, n), trans(170.0, 0, 0, n))
        t_cb = np.linalg.inv(t_oc) @ t_os
        p = np.einsum("nij,nj->ni", t_cb[ci], pb)
        u = cam["cx"] - cam["fx"] * p[:, 1] / p[:, 0]
        v = cam["cy"] - cam["fy"] * p[:, 2] / p[:, 0]
        return np.concatenate([u - uv[:, 0], v - uv[:, 1]])

    fit = least_squares(residuals, np.zeros(21), x_scale="jac")
    for k, name in enumerate(NAMES):
        unit = "mm" if "Trans" in name else "deg"
        value = fit.x[k] if unit == "mm" else np.degrees(fit.x[k])
        print(f"{name:14s} {value:10.4f} {unit}")
    rms = np.sqrt(np.mean(fit.fun**2))
    print(f"{len(rows)} vertices, {fit.nfev} evaluations, rms {rms:.4f} px; "
          f"whole process {time.perf_counter() - START:.2f} s")


if __name__ == "__main__":
    main()
