#!/usr/bin/env python3
"""The deployed skeleton's smoothing (run.pose_tau_s) swept on poses already run.

    pose_smoothing.py POSES.csv [--taus 0,0.03,0.05,0.08,0.1,0.15]

POSES.csv is what `yelan eval --run --poses` writes for a model run without smoothing
(run.pose_tau_s 0, or --pose-tau 0). The smoothing is a pure function of those poses: each
joint at unit head depth (the pose divided by its head_depth_mm) averaged exponentially over
the ticks that say "person", x += (1 - exp(-dt / tau)) (x_t - x), starting afresh after a tick
without a person and where time goes back (run::JointSmoother), then scaled by the tick's own
depth again. For each tau: MPJPE as deployed, root-aligned (hip centres) and at the true head
depth (the paper protocol), pooled over the valid joints of the poses saying "person", as
`yelan eval --run` pools them. Rerun the engine with --pose-tau at the chosen value to
confirm: it agrees within about half a millimetre (its average has run since the stream
began, while the file starts where the scoring does).
"""
import csv
import math
import sys

import numpy as np


def load(path):
    rows = [r for r in csv.DictReader(open(path)) if r["dancer"] == "1"]
    if not rows:
        sys.exit(f"{path}: no poses of recordings with a dancer")
    return rows


def joints(row, prefix):
    return np.array([[float(row[f"{prefix}j{j}_{c}"]) for c in "xyz"] for j in range(13)])


def sweep_one(rows, tau):
    dep, root, paper = [], [], []
    avg, t_prev, source = None, None, None
    for r in rows:
        if r["source"] != source:
            avg, source = None, r["source"]
        if r["person"] != "1":
            avg = None
            continue
        z = float(r["head_depth_mm"])
        pred = joints(r, "")
        if not np.all(np.isfinite(pred)) or not z > 0:
            continue
        unit = pred / z
        t = int(r["t_us"]) * 1e-6
        if avg is None or tau <= 0 or t < t_prev:
            avg = unit.copy()
        else:
            avg = avg + (1 - math.exp(-(t - t_prev) / tau)) * (unit - avg)
        t_prev = t
        q = avg * z
        truth = joints(r, "true_")
        valid = np.array([r[f"valid{j}"] == "1" for j in range(13)])
        z_true = float(r["true_head_depth_mm"])
        dep += list(np.linalg.norm(q - truth, axis=1)[valid])
        if z_true > 1:
            paper += list(np.linalg.norm(q * z_true / z - truth, axis=1)[valid])
        if valid[5] and valid[6]:
            rel = (q - (q[5] + q[6]) / 2) - (truth - (truth[5] + truth[6]) / 2)
            root += list(np.linalg.norm(rel, axis=1)[valid])
    mean = lambda v: float(np.mean(v)) if v else float("nan")
    return mean(dep), mean(root), mean(paper)


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    taus = [0, 0.03, 0.05, 0.08, 0.1, 0.15]
    if "--taus" in argv:
        i = argv.index("--taus")
        taus = [float(x) for x in argv[i + 1].split(",")]
        del argv[i:i + 2]
    rows = load(argv[0])
    print(f"{argv[0]}: {len(rows)} poses of dancer recordings")
    print("tau_s   deployed mm   root-aligned mm   true head depth mm")
    for tau in taus:
        d, r, p = sweep_one(rows, tau)
        print(f"{tau:5.3f}   {d:11.1f}   {r:15.1f}   {p:18.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
