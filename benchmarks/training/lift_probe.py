#!/usr/bin/env python3
"""Is a joint's depth learnable from the 2D skeleton? A probe outside the engine: a small MLP
(PyTorch) maps the 13 joints' image positions to their depths relative to the hip centre,
trained on the training recordings' labels and scored on the validation ones against the
per-view mean pose (the floor `yelan eval` reports as depth hip-aligned). The true 2D is
its input, so this bounds what a lifter on good 2D joints could do; the event nets' stage 2
(2026-12-01: 96.8 mm on sided sticks, 102.3 on events, floor 104) is far from it if it is low.

    /usr/bin/python3 lift_probe.py TRAIN_DIR VAL_DIR [--every 5] [--epochs 30] [--seed 1] [--noise-px S]

--noise-px S: Gaussian noise of S sensor pixels (per axis) on every joint's image position,
in training (drawn afresh each batch) and validation (drawn once): what a lifter would get
behind a net whose 2D joints are that far off (the event nets': 15 px mean distance).
"""
import argparse
import glob
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from refine_probe import fit, mlp  # noqa: E402  (the probes' MLP and its training loop)

VIEWS = ("front", "back", "left", "right")


def view_of(path):
    parts = os.path.basename(path).split("-")
    return next((v for v in VIEWS if v in parts), "?")


def load(folder, every):
    """-> (inputs N x 26, depth targets N x 13 in mm, views N, mm per pixel at the hips N):
    frames whose joints are all valid and in front of the camera, every `every`-th label."""
    xs, zs, vs, mm = [], [], [], []
    for path in sorted(glob.glob(os.path.join(folder, "*.yelan.h5"))):
        with h5py.File(path, "r") as f:
            j = f["labels/joints"][::every].astype(np.float64)
            fx = float(f["camera/K"][0, 0])
            ok = f["labels/valid"][::every].all(axis=1) & (j[..., 2] > 100).all(axis=1)
        j = j[ok]
        if not len(j):
            continue
        hip = 0.5 * (j[:, 5] + j[:, 6])
        # Each joint's image position scaled to the hip's depth (mm), relative to the hip's:
        # what the 2D skeleton shows, at the body's size, without its depth.
        xy = j[..., :2] / j[..., 2:3] * hip[:, None, 2:3] - hip[:, None, :2]
        xs.append(xy.reshape(len(j), 26))
        zs.append(j[..., 2] - hip[:, None, 2])
        vs += [view_of(path)] * len(j)
        mm.append(hip[:, 2] / fx)
    return np.concatenate(xs), np.concatenate(zs), np.array(vs), np.concatenate(mm)


def main(argv):
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("train")
    a.add_argument("val")
    a.add_argument("--every", type=int, default=5)
    a.add_argument("--epochs", type=int, default=30)
    a.add_argument("--seed", type=int, default=1)
    a.add_argument("--noise-px", type=float, default=0.0)
    o = a.parse_args(argv)
    import torch
    torch.set_num_threads(1)
    torch.manual_seed(o.seed)
    xt, zt, vt, mt = load(o.train, o.every)
    xv, zv, vv, mv = load(o.val, o.every)
    print(f"train {len(xt)} frames, val {len(xv)} frames (every {o.every}th label), 2D noise {o.noise_px} px")
    rng = np.random.default_rng(o.seed)
    xv = xv + rng.normal(0, 1, xv.shape) * o.noise_px * mv[:, None]
    floor = np.zeros_like(zv)
    for v in VIEWS:
        if (vv == v).any():
            floor[vv == v] = zt[vt == v].mean(axis=0) if (vt == v).any() else zt.mean(axis=0)
    print(f"per-view mean pose, depth hip-aligned: {np.abs(floor - zv).mean():.1f} mm a joint")
    print(f"training mean pose: {np.abs(zt.mean(axis=0) - zv).mean():.1f} mm")
    net = mlp(26, 13, 512)
    X, Z = torch.tensor(xt / 1000, dtype=torch.float32), torch.tensor(zt / 1000, dtype=torch.float32)
    M = torch.tensor(mt[:, None] * o.noise_px / 1000, dtype=torch.float32)
    Xv = torch.tensor(xv / 1000, dtype=torch.float32)

    def scored(epoch, loss):
        with torch.no_grad():
            pred = net(Xv).numpy() * 1000
        err = np.abs(pred - zv).mean(axis=0)
        print(f"epoch {epoch + 1}: depth hip-aligned {err.mean():.1f} mm a joint on validation "
              f"(train loss {1000 * loss:.1f}); per joint " + " ".join(f"{e:.0f}" for e in err))
    fit(net, len(X), lambda b: (net(X[b] + torch.randn(len(b), 26) * M[b]) - Z[b]).abs().mean(), o.epochs, scored)


if __name__ == "__main__":
    main(sys.argv[1:])
