#!/usr/bin/env python3
"""OpenCV's response calibrations on a capture's photographs, for `hprt bench capture --camera`.

Usage: opencv_response.py OUT_PREFIX TIMES GROUP [GROUP ...]
  TIMES  comma-separated exposure times (seconds), one per photograph of a group
  GROUP  comma-separated image paths: one view's photographs, in the order of TIMES

Every group is one view (an orientation or a ball picture) at every exposure. The views are put
side by side into one mosaic per exposure, so that OpenCV's calibrations (which take one
picture per exposure) sample pixels from all of them. Writes OUT_PREFIX-robertson.csv and
OUT_PREFIX-debevec.csv in the format of `hprt capture --response` (`level,r,g,b`, each channel
scaled to 1 at level 128, hprt's convention), made non-decreasing (hprt's merge inverts the
curve; OpenCV's may wiggle at the ends), and prints one line per method.

Needs Python 3 with numpy and opencv-python (4.x or later).
"""
import sys

import cv2
import numpy as np


def mosaics(groups, count):
    """One picture per exposure: the groups' photographs of that exposure side by side."""
    out = []
    for k in range(count):
        pictures = []
        for group in groups:
            picture = cv2.imread(group[k], cv2.IMREAD_COLOR)
            if picture is None:
                sys.exit(f"opencv_response.py: cannot read {group[k]}")
            pictures.append(picture)
        height = min(p.shape[0] for p in pictures)
        out.append(np.hstack([p[:height] for p in pictures]))
    return out


def write_curve(path, response):
    """OpenCV's (256, 1, 3) BGR response as hprt's CSV: RGB, 1 at level 128, non-decreasing."""
    curve = np.asarray(response, dtype=np.float64).reshape(256, 3)[:, ::-1]
    curve = np.maximum.accumulate(np.maximum(curve, 0.0), axis=0)
    curve = curve / np.maximum(curve[128], 1e-30)
    with open(path, "w") as f:
        f.write("level,r,g,b\n")
        for z in range(256):
            r, g, b = (float(v) for v in curve[z])
            f.write(f"{z},{r:.9g},{g:.9g},{b:.9g}\n")


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    prefix, times = argv[1], [float(t) for t in argv[2].split(",")]
    groups = [g.split(",") for g in argv[3:]]
    if any(len(g) != len(times) for g in groups):
        sys.exit("opencv_response.py: every group needs one photograph per exposure time")
    pictures = mosaics(groups, len(times))
    times = np.asarray(times, dtype=np.float32)
    for name, calibrate in [
        ("robertson", cv2.createCalibrateRobertson()),
        ("debevec", cv2.createCalibrateDebevec()),
    ]:
        response = calibrate.process(pictures, times)
        path = f"{prefix}-{name}.csv"
        write_curve(path, response)
        print(f"{name}: {path}")


if __name__ == "__main__":
    main(sys.argv)
