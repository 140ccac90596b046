#!/usr/bin/env python3
"""MPJPE of a `yelan eval --json` file split by the motion family in each recording's name.

    families.py EVAL.json [EVAL2.json ...]

Families: dancers in furnished rooms (`dancer-room` in the name), procedural dances
(`-dance-`) and the CMU clips (the rest). Each family's MPJPE is its recordings' frame-weighted
mean; the rows of several files are comparable only when they scored the same frames.
"""
import json
import sys


def family(name):
    if "dancer-room" in name:
        return "rooms"
    return "procedural" if "-dance-" in name else "cmu"


for path in sys.argv[1:]:
    j = json.load(open(path))
    sums = {}
    for name, row in j["by_condition"]["scene"].items():
        if not row["frames"]:  # nothing scored there (mpjpe_mm null)
            continue
        s = sums.setdefault(family(name), [0.0, 0, 0])
        s[0] += row["mpjpe_mm"] * row["frames"]
        s[1] += row["frames"]
        s[2] += 1
    parts = " ".join(f"{f} {s[0] / s[1]:.1f} ({s[2]})" for f, s in sorted(sums.items()))
    print(f"{path}: all {j['mpjpe_mm']:.1f} root-aligned {j['mpjpe_root_mm']:.1f} IoU {j['mask_iou']:.3f}; {parts}")
