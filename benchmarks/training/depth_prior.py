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
for them would give) and the true depth.

    /usr/bin/python3 benchmarks/training/depth_prior.py P.csv
"""
import csv
import math
import sys

import numpy as np

LIMBS = [(1, 3), (2, 4), (3, 7), (4, 8), (5, 9), (6, 10), (9, 11), (10, 12)]  # SPEC joint order
NO_FOREARMS = [b for b in LIMBS if b[1] not in (7, 8)]  # elbow-hand left out
DT_S = 0.02

rows = list(csv.DictReader(open(sys.argv[1])))
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
