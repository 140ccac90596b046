#!/usr/bin/env python3
"""Two pose nets compared recording by recording on the same frames.

    paired.py A.json B.json [A2.json B2.json ...]
    paired.py --poses [--root | --true-depth] [--common] A.csv B.csv [A2.csv B2.csv ...]

Each pair is two `yelan eval --json` files of the same recordings (their
by_condition.scene rows), or with --poses two `yelan eval --run --poses` files
(the deployed path's poses: each recording's MPJPE over its poses that say
"person", as the pipeline placed them, --root after aligning the hip centres,
--true-depth scaled to the true head depth, the paper protocol). The
differences B - A of all pairs are pooled. Prints their mean with its standard
error and on how many recordings B is better: a paired difference is far less
noisy than the two means side by side. --common scores only the poses both files
score (the same recording and instant, both saying "person"): a stage 1 that reports a
person more often is then not charged for the harder poses it adds.
"""
import csv
import json
import math
import sys


def scene_mpjpe(path):
    # A scene with nothing scored (mpjpe_mm null) has nothing to pair.
    return {k: v["mpjpe_mm"] for k, v in json.load(open(path))["by_condition"]["scene"].items() if v["frames"]}


def pose_errors(path, mode):
    """Each scored pose of a `yelan eval --run --poses` file: (source, t_us, mask_age, error
    summed over its valid joints, their count), in the file's order. A pose is scored where the
    recording has a dancer and the pose says "person" (with --root: both hips in the picture)."""
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["dancer"] != "1" or row["person"] != "1":
                continue
            depth, true_depth = float(row["head_depth_mm"]), float(row["true_head_depth_mm"])
            if not (depth > 0 and true_depth > 1):
                continue
            k = true_depth / depth if mode == "true-depth" else 1.0
            pred = [[k * float(row[f"j{j}_{c}"]) for c in "xyz"] for j in range(13)]
            true = [[float(row[f"true_j{j}_{c}"]) for c in "xyz"] for j in range(13)]
            valid = [row[f"valid{j}"] == "1" for j in range(13)]
            if mode == "root":
                if not (valid[5] and valid[6]):
                    continue
                rp = [(pred[5][c] + pred[6][c]) / 2 for c in range(3)]
                rt = [(true[5][c] + true[6][c]) / 2 for c in range(3)]
                pred = [[p[c] - rp[c] for c in range(3)] for p in pred]
                true = [[t[c] - rt[c] for c in range(3)] for t in true]
            n = sum(valid)
            if n:
                err = sum(math.dist(pred[j], true[j]) for j in range(13) if valid[j])
                yield row["source"], int(row["t_us"]), int(row.get("mask_age") or 0), err, n


def poses_mpjpe(path, mode, only=None):
    """Per recording, the mean distance over all scored joints (as yelan eval --run pools them);
    only: the (source, t_us) pairs to score, or None for every one."""
    sums = {}
    for source, t_us, _, err, n in pose_errors(path, mode):
        if only is not None and (source, t_us) not in only:
            continue
        s = sums.setdefault(source, [0.0, 0])
        s[0] += err
        s[1] += n
    return {k: s / n for k, (s, n) in sums.items() if n}


def mean_se(values):
    """The mean of paired differences and its standard error (NaN for a single one)."""
    n = len(values)
    mean = sum(values) / n
    return mean, math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1) / n) if n > 1 else float("nan")


def main(argv):
    mode, common = None, False
    if argv and argv[0] == "--poses":
        mode, argv = "deployed", argv[1:]
        if argv and argv[0] in ("--root", "--true-depth"):
            mode, argv = argv[0][2:], argv[1:]
        if argv and argv[0] == "--common":
            common, argv = True, argv[1:]
    if len(argv) < 2 or len(argv) % 2:
        sys.exit(__doc__)
    diffs = []
    for a, b in zip(argv[0::2], argv[1::2]):
        if mode is None:
            A, B = scene_mpjpe(a), scene_mpjpe(b)
        else:
            only = None
            if common:
                only = {(s, t) for s, t, *_ in pose_errors(a, mode)} & {(s, t) for s, t, *_ in pose_errors(b, mode)}
            A, B = poses_mpjpe(a, mode, only), poses_mpjpe(b, mode, only)
        missing = sorted(set(A) ^ set(B))
        if missing:
            sys.exit(f"{a} and {b} score different recordings, e.g. {missing[0]}")
        diffs += [B[k] - A[k] for k in A]
    n = len(diffs)
    mean, se = mean_se(diffs)
    print(f"{n} recordings: B - A = {mean:+.1f} +- {se:.1f} mm (standard error), B better on {sum(d < 0 for d in diffs)}")


if __name__ == "__main__":
    main(sys.argv[1:])
