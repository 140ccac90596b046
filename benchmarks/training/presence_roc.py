#!/usr/bin/python3
"""Presence detectors compared at every threshold, not only at their calibrated one. Reads
the poses that `yelan eval --run --poses P.csv` writes (dancer: the truth, person: the
verdict at the model's threshold, confidence: P(person)) for two or more models on the
same recordings, and prints per model: the rates at its own verdict, the area under the
ROC curve, the empty-scene rate where the dancer rate reaches 96% and 98% (issue 16 asks
>= 98% with <= 2% of empty ticks), and the dancer rate where the empty rate is 2% and 4%.
A calibration moves a model along its curve; a better stage 1 moves the curve.
--svg OUT draws the curves with issue 16's corner, a circle at each model's own verdict.

    /usr/bin/python3 benchmarks/training/presence_roc.py NAME=P.csv NAME=P.csv ... [--svg OUT.svg]
"""
import argparse
import csv
import html
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
from weights_tools.atomic import write_text_atomically  # noqa: E402  (standard library only)

ap = argparse.ArgumentParser()
ap.add_argument("runs", nargs="+", help="NAME=POSES.csv")
ap.add_argument("--svg")
args = ap.parse_args()


def load(path):
    conf, truth, verdict = [], [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            conf.append(float(row["confidence"]))
            truth.append(row["dancer"] == "1")
            verdict.append(row["person"] == "1")
    if not any(truth) or all(truth):
        sys.exit(f"{path}: needs poses with a dancer and poses of empty scenes")
    return conf, truth, verdict


def roc(conf, truth):
    """(empty rate, dancer rate) for 'person' at confidence >= t, every distinct t, high to low."""
    pos = sum(truth)
    neg = len(truth) - pos
    pairs = sorted(zip(conf, truth), key=lambda p: -p[0])
    pts, tp, fp, i = [(0.0, 0.0)], 0, 0, 0
    while i < len(pairs):
        t = pairs[i][0]
        while i < len(pairs) and pairs[i][0] == t:
            tp += pairs[i][1]
            fp += not pairs[i][1]
            i += 1
        pts.append((fp / neg, tp / pos))
    return pts


def empty_at_dancer(pts, want):
    return min(e for e, d in pts if d >= want)


def dancer_at_empty(pts, most):
    return max(d for e, d in pts if e <= most)


def auc(pts):
    return sum((e1 - e0) * (d0 + d1) / 2 for (e0, d0), (e1, d1) in zip(pts, pts[1:]))


curves, verdicts = {}, {}
print(f"{'model':<24} {'poses':>6} {'dancer':>7} {'empty':>6} {'AUC':>7} "
      f"{'empty@96':>9} {'empty@98':>9} {'dancer@2':>9} {'dancer@4':>9}")
for spec in args.runs:
    name, _, path = spec.partition("=")
    if not path:
        sys.exit(f"{spec}: expected NAME=POSES.csv")
    conf, truth, verdict = load(path)
    pts = roc(conf, truth)
    curves[name] = pts
    pos = sum(truth)
    hit = sum(v for v, t in zip(verdict, truth) if t) / pos
    fa = sum(v for v, t in zip(verdict, truth) if not t) / (len(truth) - pos)
    verdicts[name] = (fa, hit)
    print(f"{name:<24} {len(truth):>6} {100 * hit:>6.1f}% {100 * fa:>5.1f}% {auc(pts):>7.4f} "
          f"{100 * empty_at_dancer(pts, 0.96):>8.1f}% {100 * empty_at_dancer(pts, 0.98):>8.1f}% "
          f"{100 * dancer_at_empty(pts, 0.02):>8.1f}% {100 * dancer_at_empty(pts, 0.04):>8.1f}%")
print("dancer / empty: poses called person at the model's own threshold; empty@96: the share of "
      "empty poses called person at the threshold where 96% of the dancer poses are; dancer@2: "
      "the share of dancer poses called person where 2% of the empty ones are")

if args.svg:
    W, H, L, B, T, R = 560, 420, 60, 50, 30, 20
    x_max, y_min = 0.20, 0.80  # the corner that matters: few false alarms, most dancers found
    sx = lambda e: L + min(e, x_max) / x_max * (W - L - R)  # noqa: E731
    sy = lambda d: T + (1 - (max(d, y_min) - y_min) / (1 - y_min)) * (H - T - B)  # noqa: E731
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<rect x="{sx(0)}" y="{sy(1)}" width="{sx(0.02) - sx(0)}" height="{sy(0.98) - sy(1)}" fill="#dfd"/>',
           f'<text x="{sx(0.02) + 4}" y="{sy(0.98) - 4}" fill="#383">issue 16</text>']
    for k in range(0, 5):
        e = k * 0.05
        out.append(f'<line x1="{sx(e)}" y1="{sy(y_min)}" x2="{sx(e)}" y2="{sy(1)}" stroke="#eee"/>')
        out.append(f'<text x="{sx(e)}" y="{H - B + 16}" text-anchor="middle">{100 * e:.0f}%</text>')
        d = y_min + k * 0.05
        out.append(f'<line x1="{sx(0)}" y1="{sy(d)}" x2="{sx(x_max)}" y2="{sy(d)}" stroke="#eee"/>')
        out.append(f'<text x="{L - 6}" y="{sy(d) + 4}" text-anchor="end">{100 * d:.0f}%</text>')
    out.append(f'<text x="{(L + W - R) / 2}" y="{H - 12}" text-anchor="middle">poses of empty scenes called person</text>')
    out.append(f'<text transform="translate(16 {(T + H - B) / 2}) rotate(-90)" text-anchor="middle">'
               'dancer poses called person</text>')
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"]
    for n, (name, pts) in enumerate(curves.items()):
        c = colours[n % len(colours)]
        xy = []  # one vertex per pixel step: thousands of thresholds, a few hundred pixels
        for e, d in pts:
            q = (round(sx(e)), round(sy(d)))
            if e <= x_max * 1.01 and (not xy or q != xy[-1]):
                xy.append(q)
        out.append(f'<polyline points="{" ".join(f"{x},{y}" for x, y in xy)}" fill="none" stroke="{c}" stroke-width="2"/>')
        fa, hit = verdicts[name]
        out.append(f'<circle cx="{sx(fa):.1f}" cy="{sy(hit):.1f}" r="5" fill="none" stroke="{c}" stroke-width="2"/>')
        out.append(f'<text x="{W - R - 150}" y="{sy(y_min) - 12 - 16 * n}" fill="{c}">{html.escape(name)}</text>')
    out.append("</svg>")
    write_text_atomically(args.svg, "\n".join(out) + "\n")
    print(f"wrote {args.svg}")
