#!/usr/bin/env python3
"""The plain Python OpenCV loop naocalib's detection is compared with.

    python3 scripts/detect_opencv.py DATASET [--sb] [--truth CORNERS.csv]

For every image a dataset's captures.csv names: read it as grey, findChessboardCorners
(adaptive threshold, normalised image, fast check; or findChessboardCornersSB with --sb)
on the whole image, cornerSubPix in a 5 px half-window; single-threaded. Prints how many
boards were found and the wall time of the loop and of the whole process. With --truth
(a corners.csv of true positions, e.g. written from a simulation), also the RMS distance
of each detected point to the nearest true vertex of its capture (OpenCV's numbering is
not the board's, so no (row, col) is checked).

Needs `pip install opencv-python-headless numpy`.
"""

import argparse
import csv
import os
import sys
import time

START = time.perf_counter()

import cv2  # noqa: E402
import numpy as np  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dataset")
    ap.add_argument("--pattern", default="6x4")
    ap.add_argument("--sb", action="store_true")
    ap.add_argument("--truth")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    cols, rows = (int(x) for x in args.pattern.lower().split("x"))
    with open(os.path.join(args.dataset, "captures.csv"), newline="") as f:
        captures = [(int(r["capture"]), r["image"]) for r in csv.DictReader(f) if r["image"]]
    truth = {}
    if args.truth:
        with open(args.truth, newline="") as f:
            for r in csv.DictReader(f):
                truth.setdefault(int(r["capture"]), []).append((float(r["u"]), float(r["v"])))
    flags = (
        cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK
    )
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    found, errors = 0, []
    loop = time.perf_counter()
    for capture, image in captures:
        grey = cv2.imread(os.path.join(args.dataset, image), cv2.IMREAD_GRAYSCALE)
        if grey is None:
            continue
        if args.sb:
            ok, corners = cv2.findChessboardCornersSB(grey, (cols, rows))
        else:
            ok, corners = cv2.findChessboardCorners(grey, (cols, rows), flags)
            if ok:
                corners = cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1), criteria)
        if not ok:
            continue
        found += 1
        if capture in truth:
            t = np.array(truth[capture])
            for p in corners.reshape(-1, 2):
                errors.append(np.min(np.hypot(t[:, 0] - p[0], t[:, 1] - p[1])))
    end = time.perf_counter()
    line = (
        f"{len(captures)} images: {found} found; loop {end - loop:.2f} s "
        f"({len(captures) / (end - loop):.0f} images/s), whole process {end - START:.2f} s"
    )
    if errors:
        line += f"; RMS {np.sqrt(np.mean(np.square(errors))):.4f} px over {len(errors)} points"
    print(line)


if __name__ == "__main__":
    sys.exit(main())
