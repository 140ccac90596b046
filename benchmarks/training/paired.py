#!/usr/bin/env python3
"""Two pose nets compared recording by recording on the same frames.

    paired.py A.json B.json [A2.json B2.json ...]

Each pair is two `yelan eval --json` files of the same recordings (their
by_condition.scene rows); the differences B - A of all pairs are pooled. Prints
their mean with its standard error and on how many recordings B is better:
a paired difference is far less noisy than the two means side by side.
"""
import json
import math
import sys


def scene_mpjpe(path):
    return {k: v["mpjpe_mm"] for k, v in json.load(open(path))["by_condition"]["scene"].items()}


def main(argv):
    if len(argv) < 2 or len(argv) % 2:
        sys.exit(__doc__)
    diffs = []
    for a, b in zip(argv[0::2], argv[1::2]):
        A, B = scene_mpjpe(a), scene_mpjpe(b)
        missing = sorted(set(A) ^ set(B))
        if missing:
            sys.exit(f"{a} and {b} score different recordings, e.g. {missing[0]}")
        diffs += [B[k] - A[k] for k in A]
    n = len(diffs)
    mean = sum(diffs) / n
    se = math.sqrt(sum((d - mean) ** 2 for d in diffs) / (n - 1) / n) if n > 1 else float("nan")
    print(f"{n} recordings: B - A = {mean:+.1f} +- {se:.1f} mm (standard error), B better on {sum(d < 0 for d in diffs)}")


if __name__ == "__main__":
    main(sys.argv[1:])
