#!/usr/bin/env python3
"""Weight averaging ("model soup") of runs that share an ancestor.

    average_weights.py OUT.h5 A.h5 B.h5 [C.h5 ...] [--groups mask,pose]

Every tensor of the named groups (default: mask) is the mean of the inputs' tensors,
BatchNorm's running statistics included (num_batches_tracked is the first file's); the
other groups and the config are the first file's. The inputs must hold the same tensors.
Written atomically. The fifty-second session's experiment: mask-s51, -s52 and -s53 (three
600-step rounds in sequence from mask-s43) averaged, scored as deployed on the validation
dancers by candidate.sh: mask IoU 0.750 against mask-s52's 0.752 (models/README.md)."""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
from weights_tools.h5weights import WeightsError, read_weights, write_weights  # noqa: E402


def average(paths, groups):
    cfg, first = read_weights(paths[0])
    others = [read_weights(p)[1] for p in paths[1:]]
    out = {g: dict(t) for g, t in first.items()}
    for g in groups:
        for p, o in zip(paths[1:], others):
            if set(o[g]) != set(first[g]):
                raise WeightsError(f"{p}: /{g} holds other tensors than {paths[0]}")
        for key, t in first[g].items():
            if key.endswith(".num_batches_tracked"):
                continue
            for p, o in zip(paths[1:], others):
                if o[g][key].shape != t.shape:
                    raise WeightsError(f"{p}: /{g}/{key} has shape {o[g][key].shape}, {paths[0]} {t.shape}")
            out[g][key] = np.mean([t.astype(np.float64)] + [o[g][key].astype(np.float64) for o in others],
                                  axis=0).astype(np.float32)
    return json.dumps(cfg), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("--groups", default="mask")
    a = ap.parse_args()
    if len(a.inputs) < 2:
        ap.error("give at least two weights files to average")
    groups = a.groups.split(",")
    if any(g not in ("mask", "pose") for g in groups):
        ap.error("--groups: mask, pose or mask,pose")
    try:
        cfg_json, groups_out = average(a.inputs, groups)
    except WeightsError as e:
        sys.exit(f"average_weights.py: {e}")
    write_weights(a.out, cfg_json, groups_out)
    print(f"wrote {a.out}: /{', /'.join(groups)} the mean of {len(a.inputs)} files")


if __name__ == "__main__":
    main()
