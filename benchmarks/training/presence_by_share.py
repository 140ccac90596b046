#!/usr/bin/env python3
"""The "person" verdict on dancer poses, by how much of the dancer shows.

    presence_by_share.py POSES.csv RECORDINGS_DIR

POSES.csv is what `yelan eval --run --data RECORDINGS_DIR --poses` writes. Each pose of a
dancer recording with a joint in the picture is binned by the share of the frame its
dancer's true mask covers (after occlusion; the latest mask at or before the pose), and each
bin says how many of its poses said "no person". A share of 0 is a dancer wholly hidden:
nothing for an event camera to see.
"""
import bisect
import collections
import csv
import sys

import h5py
import numpy as np

BINS = [0, 1e-9, 0.002, 0.005, 0.01, 0.02, 1.01]


def main(argv):
    if len(argv) != 2:
        print(__doc__)
        return 2
    rows = [r for r in csv.DictReader(open(argv[0])) if r["dancer"] == "1"]
    by_source = collections.defaultdict(list)
    for r in rows:
        by_source[r["source"]].append(r)
    count, missed = collections.Counter(), collections.Counter()
    for source, poses in by_source.items():
        with h5py.File(f"{argv[1]}/{source}.yelan.h5", "r") as f:
            mask_t = f["masks/t"][:]
            masks = f["masks/data"]
            share = np.array([(masks[i] > 0).mean() for i in range(len(mask_t))])
        for r in poses:
            if not any(r[f"valid{j}"] == "1" for j in range(13)):
                continue
            s = share[max(0, bisect.bisect_right(mask_t, int(r["t_us"])) - 1)]
            b = next(k for k in range(len(BINS) - 1) if BINS[k] <= s < BINS[k + 1])
            count[b] += 1
            missed[b] += r["person"] != "1"
    print("dancer's share of the frame   poses   said no person")
    for b in sorted(count):
        name = "0 (wholly hidden)" if b == 0 else f"({BINS[b]:.3f}, {min(BINS[b + 1], 1):.3f})"
        print(f"{name:>17}   {count[b]:14d}   {missed[b]:5d} ({100 * missed[b] / count[b]:.1f}%)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
