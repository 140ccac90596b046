#!/usr/bin/python3
"""Recordings whose events are the labelled skeleton alone: a diagnostic for stage 2.

Each recording of SRC (yelan sim's *.yelan.h5) is copied to DST with its camera, labels and
attributes, but its events replaced: at every label time, ON events on every pixel of the
projected skeleton's 14 bones (one-pixel lines through the valid joints) and OFF events on
the pixels the previous label's bones covered and these do not; its masks all ones (the
whole frame: no stage-1 cut). The TORE of such a stream is a clean stick figure with its
trail. A pose net that cannot learn to read joints from it cannot read them from a dancer
either; one that can, but not from a dancer's events, is limited by what the events show.

--sided: the body's sides told apart by polarity, and no OFF trail: the right side's bones
(head to right shoulder, right arm and leg, right flank) draw ON events, the left side's OFF
events, the shoulder and hip lines both. A plain stick figure seen from the back is the one
seen from the front mirrored, left and right traded: a net must guess which side is which and
can only hedge; sided sticks say it. Where they read far better, telling the sides apart is what
holds the net, not reading the limbs.

    stick_figure.py SRC_DIR DST_DIR [--limit N] [--dancers-only] [--sided]
"""
import argparse
import json
import os
import sys

import h5py
import numpy as np

# SPEC: head-shoulders, shoulder-elbow-hand, shoulder-hip-knee-foot, shoulders, hips.
EDGES = [(0, 1), (0, 2), (1, 3), (3, 7), (2, 4), (4, 8), (1, 5), (5, 9), (9, 11), (2, 6), (6, 10), (10, 12),
         (1, 2), (5, 6)]
# Joints 1, 3, 5, 7, 9, 11 are the right side's (SPEC order), 2, 4, ... the left's.
RIGHT = [e for e in EDGES if all(j == 0 or j % 2 == 1 for j in e)]
LEFT = [e for e in EDGES if all(j == 0 or j % 2 == 0 for j in e)]


def skeleton_pixels(joints, valid, K, width, height, edges=EDGES):
    """Flat pixel indices (y * width + x) of the projected bones of one label, unique."""
    z = joints[:, 2]
    ok = (valid > 0) & (z > 1.0)
    u = K[0, 0] * joints[:, 0] / np.where(ok, z, 1.0) + K[0, 2]
    v = K[1, 1] * joints[:, 1] / np.where(ok, z, 1.0) + K[1, 2]
    out = []
    for a, b in edges:
        if not (ok[a] and ok[b]):
            continue
        n = int(np.ceil(max(abs(u[b] - u[a]), abs(v[b] - v[a])))) + 1
        s = np.linspace(0.0, 1.0, min(n, 4000))
        x = np.rint(u[a] + s * (u[b] - u[a])).astype(np.int64)
        y = np.rint(v[a] + s * (v[b] - v[a])).astype(np.int64)
        keep = (x >= 0) & (x < width) & (y >= 0) & (y < height)
        out.append(y[keep] * width + x[keep])
    return np.unique(np.concatenate(out)) if out else np.zeros(0, np.int64)


def convert(src, dst, sided=False):
    with h5py.File(src, "r") as f:
        K = f["camera/K"][()]
        width, height = int(f["camera/width"][()]), int(f["camera/height"][()])
        lt, joints, valid = f["labels/t"][()], f["labels/joints"][()], f["labels/valid"][()]
        mt = f["masks/t"][()]
        duration_us = int(f["events/t"][-1]) + 1 if f["events/t"].shape[0] else int(lt[-1]) + 1
        tmp = dst + ".part"
        with h5py.File(tmp, "w") as g:
            for k, v in f.attrs.items():
                g.attrs[k] = v
            scene = json.loads(f.attrs["scene"]) if "scene" in f.attrs else {}
            scene["stick_figure"] = True
            g.attrs["scene"] = json.dumps(scene)
            f.copy("camera", g)
            f.copy("labels", g)
            ts, xs, ys, ps = [], [], [], []
            prev = np.zeros(0, np.int64)
            for i in range(lt.shape[0]):
                if sided:
                    on = skeleton_pixels(joints[i], valid[i], K, width, height, [e for e in EDGES if e not in LEFT])
                    off = skeleton_pixels(joints[i], valid[i], K, width, height, [e for e in EDGES if e not in RIGHT])
                    drawn = ((off, 0), (on, 1))
                else:
                    cur = skeleton_pixels(joints[i], valid[i], K, width, height)
                    drawn = ((np.setdiff1d(prev, cur, assume_unique=True), 0), (cur, 1))
                    prev = cur
                for pix, pol in drawn:
                    ts.append(np.full(pix.shape[0], lt[i], np.int64))
                    xs.append((pix % width).astype(np.uint16))
                    ys.append((pix // width).astype(np.uint16))
                    ps.append(np.full(pix.shape[0], pol, np.uint8))
            t = np.concatenate(ts)
            ev = g.create_group("events")
            for name, col in (("t", t), ("x", np.concatenate(xs)), ("y", np.concatenate(ys)), ("p", np.concatenate(ps))):
                ev.create_dataset(name, data=col, chunks=(min(65536, max(1, col.shape[0])),), compression="gzip",
                                  compression_opts=1)
            ms = np.arange(0, duration_us // 1000 + 1, dtype=np.int64) * 1000
            idx = np.searchsorted(t, ms, side="left").astype(np.uint64)
            d = ev.create_dataset("ms_to_idx", data=idx, chunks=(min(4096, idx.shape[0]),), compression="gzip")
            d.attrs["t0_us"] = 0
            m = g.create_group("masks")
            m.create_dataset("t", data=mt)
            m.create_dataset("data", data=np.ones((mt.shape[0], height, width), np.uint8), chunks=(1, height, width),
                             compression="gzip", compression_opts=1)
        os.replace(tmp, dst)
    return t.shape[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--limit", type=int, default=0, help="at most this many recordings (every k-th by name)")
    ap.add_argument("--dancers-only", action="store_true", help="skip recordings with nobody (empty rooms)")
    ap.add_argument("--sided", action="store_true", help="right side's bones ON events, left side's OFF")
    a = ap.parse_args()
    names = sorted(n for n in os.listdir(a.src) if n.endswith(".yelan.h5"))
    if a.dancers_only:
        def dancer(n):
            with h5py.File(os.path.join(a.src, n), "r") as f:
                return int(f.attrs.get("dancer", 1)) == 1
        names = [n for n in names if dancer(n)]
    if a.limit and len(names) > a.limit:
        step = len(names) / a.limit
        names = [names[int(i * step)] for i in range(a.limit)]
    os.makedirs(a.dst, exist_ok=True)
    for i, n in enumerate(names):
        out = os.path.join(a.dst, n)
        if os.path.exists(out):
            continue
        events = convert(os.path.join(a.src, n), out, a.sided)
        print(f"[{i + 1}/{len(names)}] {n}: {events} events", file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
