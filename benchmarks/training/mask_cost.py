#!/usr/bin/python3
"""What stage 1's masks cost a stage 2, split by how well stage 1 did on each recording.

    /usr/bin/python3 benchmarks/training/mask_cost.py [--iou 0.5] NAME=TRUE.json:NET.json ...

TRUE.json and NET.json: `yelan eval --json` of one model on the same recordings, with
--true-mask and without (behind stage 1's masks). Stage 1's IoU per recording is read from
the first NET.json given (the same stage 1 throughout: only stage 2 differs). For each model
prints the MPJPE (frame-weighted) behind the true and behind stage 1's masks, on the
recordings where stage 1's IoU is at least --iou and on the rest, and the median cost per
recording: a mean hides whether the masks cost a little everywhere or all on a few.
"""
import argparse
import json
import statistics


def scenes(path):
    try:
        with open(path) as f:
            j = json.load(f)
        return j["by_condition"]["scene"], j.get("mask_iou_by_condition", {}).get("scene")
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise SystemExit(f"mask_cost.py: {path}: not a `yelan eval --json` file with per-scene scores ({e!r})")


def mean(rows, keys):
    frames = sum(rows[k]["frames"] for k in keys)
    return sum(rows[k]["mpjpe_mm"] * rows[k]["frames"] for k in keys if rows[k]["frames"]) / frames if frames else float("nan")


ap = argparse.ArgumentParser()
ap.add_argument("--iou", type=float, default=0.5, help="stage 1's IoU that splits the recordings")
ap.add_argument("runs", nargs="+", help="NAME=TRUE.json:NET.json")
args = ap.parse_args()

iou = None
models = []
for arg in args.runs:
    name, _, pair = arg.partition("=")
    true_path, _, net_path = pair.partition(":")
    if not net_path:
        ap.error(f"'{arg}': expected NAME=TRUE.json:NET.json")
    true_rows, _ = scenes(true_path)
    net_rows, net_iou = scenes(net_path)
    if iou is None:
        if not net_iou:
            raise SystemExit(f"mask_cost.py: {net_path}: no mask IoU per scene (scored with --true-mask?)")
        iou = net_iou
    models.append((name, true_rows, net_rows))

common = sorted(set(iou).intersection(*(set(t) & set(n) for _, t, n in models)))
good = [k for k in common if iou[k] >= args.iou]
poor = [k for k in common if iou[k] < args.iou]
print(f"{len(common)} recordings: stage 1's IoU >= {args.iou} on {len(good)}, below on {len(poor)}")
for k in poor:
    print(f"  IoU {iou[k]:.3f}  {k}")
width = max(len(m[0]) for m in models)
print(f"{'':{width}}  {'IoU >= cut: true / stage 1 mm':>31}  {'below: true / stage 1 mm':>25}  {'median cost mm':>14}")
for name, t, n in models:
    cost = statistics.median(n[k]["mpjpe_mm"] - t[k]["mpjpe_mm"] for k in common if n[k]["frames"] and t[k]["frames"])
    print(f"{name:{width}}  {mean(t, good):14.1f} / {mean(n, good):6.1f}      {mean(t, poor):10.1f} / {mean(n, poor):6.1f}  {cost:14.1f}")
