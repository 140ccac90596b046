#!/usr/bin/python3
"""How should `yelan run` turn a pose up to scale into millimetres? Reads the poses that
`yelan eval --run --poses P.csv` writes (a run of a model without depth smoothing, its
8-limb prior) and scores other depth estimates on the same poses: the prior's limb sum
with or without the forearms, the ln-depth averaged over time with time constants tau
(as run::DepthSmoother: ticks with a person, afresh on each recording), each with its
scale fitted as `weights calibrate` fits run.depth_scale (the median of truth / estimate).
Prints the deployed MPJPE and the mean head-depth error, on all recordings and on the
even / odd halves by name (a choice that holds on both is not one recording's luck), and
the oracles: a scale per recording (what knowing each dancer's size and the net's bias
for them would give) and the true depth. --svg OUT draws one recording's head depth over
time (REC: its name, default the first): the truth, the 8-limb prior, and the prior without
forearms averaged over 0.5 s.

    /usr/bin/python3 benchmarks/training/depth_prior.py P.csv [--svg OUT.svg [--recording REC]]
"""
import argparse
import csv
import html
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
from weights_tools.atomic import write_text_atomically  # noqa: E402  (standard library only)

ap = argparse.ArgumentParser()
ap.add_argument("poses")
ap.add_argument("--svg")
ap.add_argument("--recording")
args = ap.parse_args()

LIMBS = [(1, 3), (2, 4), (3, 7), (4, 8), (5, 9), (6, 10), (9, 11), (10, 12)]  # SPEC joint order
NO_FOREARMS = [b for b in LIMBS if b[1] not in (7, 8)]  # elbow-hand left out
DT_S = 0.02

rows = list(csv.DictReader(open(args.poses)))
recs = {}
for r in rows:
    if r['dancer'] != '1' or r['person'] != '1':
        continue
    z = float(r['head_depth_mm'])
    joints = np.array([[float(r[f'j{j}_{c}']) for c in 'xyz'] for j in range(13)])
    truth = np.array([[float(r[f'true_j{j}_{c}']) for c in 'xyz'] for j in range(13)])
    valid = np.array([int(r[f'valid{j}']) for j in range(13)]) > 0
    recs.setdefault(r['source'], []).append((joints / z, float(r['true_head_depth_mm']), truth, valid))


def score(rs, depths):
    errs, dz = [], []
    for name, poses in rs.items():
        for (unit, zt, truth, valid), z in zip(poses, depths[name]):
            errs.extend(np.linalg.norm(unit * z - truth, axis=1)[valid])
            dz.append(abs(z - zt))
    return np.mean(errs), np.mean(dz)


def estimate(rs, bones, tau):
    raw = {n: [1 / sum(np.linalg.norm(u[i] - u[j]) for i, j in bones) for (u, _, _, _) in p] for n, p in rs.items()}
    out = {}
    for n, zs in raw.items():
        m, sm = None, []
        for z in zs:
            x = math.log(z)
            m = x if m is None or tau == 0 else m + (1 - math.exp(-DT_S / tau)) * (x - m)
            sm.append(math.exp(m))
        out[n] = sm
    s = np.median([zt / z for n, p in rs.items() for (_, zt, _, _), z in zip(p, out[n])])
    return {n: [s * z for z in zs] for n, zs in out.items()}


names = sorted(recs)
print(f'{len(recs)} recordings, {sum(len(p) for p in recs.values())} poses with a person')
for half in ('all', 'even', 'odd'):
    rs = {n: recs[n] for i, n in enumerate(names) if half == 'all' or i % 2 == (half == 'odd')}
    for label, bones in (('limbs', LIMBS), ('no forearms', NO_FOREARMS)):
        for tau in (0, 0.25, 0.5, 1, 2):
            e, d = score(rs, estimate(rs, bones, tau))
            print(f'{half:4s}  {label:11s}  tau {tau:4.2f} s:  MPJPE {e:6.1f} mm  |dz| {d:6.1f} mm')
base = estimate(recs, LIMBS, 0)
per_rec = {n: [z * np.median([p[1] / y for p, y in zip(recs[n], zs)]) for z in zs] for n, zs in base.items()}
print('oracle, a scale per recording (limbs, tau 0):  MPJPE %.1f mm  |dz| %.1f mm' % score(recs, per_rec))
print('oracle, the true head depth:  MPJPE %.1f mm' % score(recs, {n: [p[1] for p in recs[n]] for n in recs})[0])


def depth_chart(name):
    """One recording's head depth over time, as an SVG: truth and two estimates."""
    one = {name: recs[name]}
    t = np.arange(len(recs[name])) * DT_S
    series = [("true head depth", [p[1] for p in recs[name]], "#000000"),
              ("prior, 8 limbs, each tick", estimate(recs, LIMBS, 0)[name], "#d62728"),
              ("prior without forearms, averaged over 0.5 s", estimate(recs, NO_FOREARMS, 0.5)[name], "#1f77b4")]
    lo = min(min(v) for _, v, _ in series) * 0.97
    hi = max(max(v) for _, v, _ in series) * 1.03
    W, H, L, B = 720, 360, 70, 50
    X = lambda x: L + (x / max(t[-1], 1e-9)) * (W - L - 20)
    Y = lambda y: H - B - (y - lo) / (hi - lo) * (H - B - 40)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{L}" y="20" font-size="14">{html.escape(name)}: head depth as deployed</text>',
           f'<line x1="{L}" y1="{H - B}" x2="{W - 20}" y2="{H - B}" stroke="#444"/>',
           f'<line x1="{L}" y1="40" x2="{L}" y2="{H - B}" stroke="#444"/>',
           f'<text x="{(W + L) / 2}" y="{H - 12}" text-anchor="middle">time (s)</text>',
           f'<text x="16" y="{(H - B + 40) / 2}" transform="rotate(-90 16 {(H - B + 40) / 2})" text-anchor="middle">head depth (mm)</text>']
    for k in range(6):
        y = lo + (hi - lo) * k / 5
        out.append(f'<text x="{L - 6}" y="{Y(y) + 4:.1f}" text-anchor="end">{y:.0f}</text>')
        out.append(f'<line x1="{L}" y1="{Y(y):.1f}" x2="{W - 20}" y2="{Y(y):.1f}" stroke="#eee"/>')
    for s in range(int(t[-1]) + 1):
        out.append(f'<text x="{X(s):.1f}" y="{H - B + 16}" text-anchor="middle">{s}</text>')
    for i, (label, v, colour) in enumerate(series):
        pts = " ".join(f"{X(x):.1f},{Y(y):.1f}" for x, y in zip(t, v))
        out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="{2 if i == 0 else 1.3}" points="{pts}"/>')
        e = np.mean(np.abs(np.array(v) - np.array(series[0][1])))
        out.append(f'<text x="{L + 10}" y="{58 + 16 * i}" fill="{colour}">{html.escape(label)}'
                   + (f" (mean |error| {e:.0f} mm)" if i else "") + "</text>")
    out.append("</svg>\n")
    return "\n".join(out)


if args.svg:
    name = args.recording or names[0]
    if name not in recs:
        sys.exit(f"{args.poses}: no recording named {name} with a person in it")
    write_text_atomically(args.svg, depth_chart(name))
    print(f"wrote {args.svg}")
