#!/usr/bin/python3
"""Which of stage 1's cues tell a dancer from an empty scene? Reads the ticks that
`yelan weights calibrate --ticks T.csv` writes and fits class-balanced logistic laws on
sets of cues (the mask's share, its mean probability inside the cut, its largest blob's
share, stage 1's score, the pose net's heatmap peak), also averaged over the last k ticks;
prints the rates in-sample and 2-fold by recording (even / odd recordings by name).

    /usr/bin/python3 benchmarks/training/presence_cues.py T.csv
"""
import csv
import sys

import numpy as np

rows = list(csv.DictReader(open(sys.argv[1])))
rec = np.array([r['recording'] for r in rows])
t = np.array([int(r['t_us']) for r in rows])
y = np.array([int(r['person']) for r in rows], float)
F = {k: np.array([float(r[k]) for r in rows]) for k in ['share', 'mask_mean_p', 'mask_blob', 'mask_score', 'pose_confidence']}
F['lshare'] = np.log(F['share'] + 1e-3)
F['lblob'] = np.log(F['share'] * F['mask_blob'] + 1e-3)
q = np.clip(F['mask_mean_p'], 1e-3, 1 - 1e-3)
F['logit_p'] = np.log(q / (1 - q))
room = np.array(['room' in r for r in rec])
folds = {r: i % 2 for i, r in enumerate(sorted(set(rec)))}
fold = np.array([folds[r] for r in rec])


def causal_mean(x, k):
    """Each tick's mean over the last k ticks of its recording."""
    out = np.empty_like(x)
    for r in np.unique(rec):
        idx = np.where(rec == r)[0]
        idx = idx[np.argsort(t[idx])]
        c = np.concatenate([[0], np.cumsum(x[idx])])
        n = np.arange(1, len(idx) + 1)
        lo = np.maximum(0, n - k)
        out[idx] = (c[n] - c[lo]) / (n - lo)
    return out


def fit(X, y, w, ridge=1e-3):
    X = np.hstack([X, np.ones((len(X), 1))])
    th = np.zeros(X.shape[1])
    for _ in range(100):
        p = 1 / (1 + np.exp(-X @ th))
        g = X.T @ (w * (p - y)) + ridge * np.r_[th[:-1], 0]
        H = (X * (w * p * (1 - p))[:, None]).T @ X + ridge * np.eye(len(th))
        th -= np.linalg.solve(H, g)
    return th


def balanced(y):
    return np.where(y == 1, 0.5 / y.sum(), 0.5 / (1 - y).sum())


def prob(X, th):
    return 1 / (1 + np.exp(-(np.hstack([X, np.ones((len(X), 1))]) @ th)))


def evaluate(names, k=1):
    X = np.stack([causal_mean(F[n], k) if k > 1 else F[n] for n in names], 1)
    th = fit(X, y, balanced(y))
    p = prob(X, th)
    pc = np.empty_like(y)
    for f in (0, 1):
        tr = fold != f
        pc[~tr] = prob(X[~tr], fit(X[tr], y[tr], balanced(y[tr])))
    print(f"{'+'.join(names):45s} k={k:2d} in-sample hit {100 * (p[y == 1] >= .5).mean():5.1f} "
          f"fa {100 * (p[y == 0] >= .5).mean():5.1f} | 2-fold hit {100 * (pc[y == 1] >= .5).mean():5.1f} "
          f"fa {100 * (pc[y == 0] >= .5).mean():5.1f} | fa rooms {100 * (pc[(y == 0) & room] >= .5).mean():5.1f} "
          f"hit dancer-rooms {100 * (pc[(y == 1) & room] >= .5).mean():5.1f}  th {np.round(th, 2)}")


all4 = ['lshare', 'logit_p', 'mask_blob', 'pose_confidence']
for names in [['lshare'], ['lshare', 'logit_p'], ['lshare', 'mask_blob'], ['lshare', 'mask_score'],
              ['lshare', 'pose_confidence'], ['lblob'], ['lshare', 'logit_p', 'mask_blob'], all4, all4 + ['mask_score']]:
    evaluate(names)
for k in [3, 5, 10, 25]:
    evaluate(['lshare'], k)
    evaluate(all4, k)
for n in ['lshare', 'mask_mean_p', 'mask_blob', 'mask_score', 'pose_confidence']:
    print(n, 'person q10/50/90', np.round(np.quantile(F[n][y == 1], [.1, .5, .9]), 3),
          'empty', np.round(np.quantile(F[n][y == 0], [.1, .5, .9]), 3))
