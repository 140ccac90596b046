#!/usr/bin/python3
"""How well could any net do that only recalls training poses? For each labelled pose of the
query recordings, the nearest labelled pose of the training recordings (MPJPE over the 13
joints, both root-aligned at the hip centre), in two frames:
  camera: the poses as the camera sees them (facing and pitch included), the lookup a net
          would make from the image alone;
  body:   each pose turned about the world's vertical so its hips face one way, the
          lookup if the facing were known: how much of the motion itself the training
          data holds.
Printed per motion family (CMU clip or procedural dance), beside the per-view mean pose
of the training poses (the floor yelan eval prints, here on these poses). --eval E.json (the
`yelan eval --json` of a net on the query recordings, scored over their first --seconds):
per recording, how the net's root-aligned error follows the lookup's distance and the floor.
--poses P.csv (`yelan eval --poses` of a net on the query recordings): the same frame by frame,
each scored frame with all 13 joints valid against its own lookup (camera frame, same view),
by quartile of the lookup's distance. --shares: the lookup from 1/16, 1/8, ... of the
training recordings (drawn with --seed): how the coverage grows with recordings.

usage: pose_coverage.py --train DIR [DIR...] --query DIR [--label-step 10] [--query-step 6]
                        [--seconds S] [--eval E.json ...] [--poses P.csv] [--shares] [--seed 1]
"""
import argparse
import json
import os
import sys

import h5py
import numpy as np

HIP_R, HIP_L = 5, 6
HAND_R, HAND_L = 7, 8


def recordings(folder):
    for name in sorted(os.listdir(folder)):
        if name.endswith(".yelan.h5"):
            yield os.path.join(folder, name)


def load(folder, step, seconds=None):
    """(poses_cam, poses_body, view, family, recording) of every dancer recording's labels,
    every step-th label (of the first `seconds`), root-aligned, joints never invalid."""
    cam, body, views, fams, recs = [], [], [], [], []
    for path in recordings(folder):
        with h5py.File(path, "r") as f:
            if not int(f.attrs.get("dancer", 0)) or "labels" not in f:
                continue
            j = f["labels/joints"][::step].astype(np.float64)
            valid = f["labels/valid"][::step].astype(bool)
            t = f["labels/t"][::step]
            M = f["camera/M"][()]
            scene = json.loads(f.attrs["scene"])
        keep = valid.all(axis=1)
        if seconds is not None:
            keep &= t - t[0] < seconds * 1e6
        j = j[keep]
        if len(j) == 0:
            continue
        root = 0.5 * (j[:, HIP_R] + j[:, HIP_L])
        rel = j - root[:, None, :]
        # camera -> world rotation: M = [R | t] maps world to camera, so world = R^T cam.
        R = M[:, :3]
        w = rel @ R  # (n, 13, 3): each row r -> R^T r
        hips = w[:, HIP_L] - w[:, HIP_R]
        ang = np.arctan2(hips[:, 1], hips[:, 0])
        c, s = np.cos(-ang), np.sin(-ang)
        b = w.copy()
        b[..., 0] = c[:, None] * w[..., 0] - s[:, None] * w[..., 1]
        b[..., 1] = s[:, None] * w[..., 0] + c[:, None] * w[..., 1]
        cam.append(rel)
        body.append(b)
        views += [scene["view"]] * len(j)
        motion = scene["motion"]
        fams += ["procedural" if motion == "dance" else "CMU"] * len(j)
        recs += [os.path.basename(path).split(".")[0]] * len(j)
    return (np.concatenate(cam), np.concatenate(body), np.array(views), np.array(fams), np.array(recs))


def nearest_mpjpe(train, query, shortlist=16, chunk=512):
    """Per query pose, the smallest MPJPE to any training pose (L2 shortlist, exact MPJPE)."""
    T = train.reshape(len(train), -1)
    tn = (T * T).sum(1)
    out = np.empty(len(query))
    hands = np.empty(len(query))
    for i in range(0, len(query), chunk):
        q = query[i:i + chunk]
        Q = q.reshape(len(q), -1)
        d2 = (Q * Q).sum(1)[:, None] - 2 * Q @ T.T + tn[None, :]
        k = min(shortlist, len(train) - 1)
        idx = np.argpartition(d2, k, axis=1)[:, :k + 1]
        cand = train[idx]  # (m, k, 13, 3)
        err = np.linalg.norm(cand - q[:, None], axis=3)  # (m, k, 13)
        m = err.mean(axis=2)
        best = m.argmin(axis=1)
        out[i:i + chunk] = m[np.arange(len(q)), best]
        hands[i:i + chunk] = err[np.arange(len(q)), best][:, [HAND_R, HAND_L]].mean(axis=1)
    return out, hands


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="+", required=True)
    ap.add_argument("--query", required=True)
    ap.add_argument("--label-step", type=int, default=10, help="every n-th training label (300 Hz)")
    ap.add_argument("--query-step", type=int, default=6, help="every n-th query label")
    ap.add_argument("--seconds", type=float, help="only the query recordings' first seconds")
    ap.add_argument("--eval", nargs="*", default=[], help="yelan eval --json of nets on the query recordings")
    ap.add_argument("--poses", help="yelan eval --poses CSV of a net on the query recordings")
    ap.add_argument("--shares", action="store_true", help="the lookup from shares of the training recordings")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    parts = [load(d, a.label_step) for d in a.train]
    tc, tb, tv, _, tr = (np.concatenate([p[i] for p in parts]) for i in range(5))
    qc, qb, qv, qf, qr = load(a.query, a.query_step, a.seconds)
    print(f"training poses {len(tc)} from {' '.join(a.train)}; query poses {len(qc)} from {a.query}")
    nn_cam = np.empty(len(qc)); nn_cam_h = np.empty(len(qc))
    floor = np.empty(len(qc))
    for v in np.unique(qv):
        sel, tsel = qv == v, tv == v
        nn_cam[sel], nn_cam_h[sel] = nearest_mpjpe(tc[tsel], qc[sel])
        mean = tc[tsel].mean(axis=0)
        floor[sel] = np.linalg.norm(qc[sel] - mean, axis=2).mean(axis=1)
    nn_body, nn_body_h = nearest_mpjpe(tb, qb)
    print(f"{'family':<12}{'poses':>7}{'per-view mean (floor)':>23}{'nearest, camera':>17}{'nearest, body':>15}"
          f"{'hands cam/body':>16}")
    for fam in ["all", "CMU", "procedural"]:
        sel = np.ones(len(qc), bool) if fam == "all" else qf == fam
        if not sel.any():
            continue
        print(f"{fam:<12}{sel.sum():>7}{floor[sel].mean():>23.1f}{nn_cam[sel].mean():>17.1f}{nn_body[sel].mean():>15.1f}"
              f"{nn_cam_h[sel].mean():>9.1f} /{nn_body_h[sel].mean():>5.1f}")
    for q in (50, 90):
        print(f"  CMU {q}th percentile: camera {np.percentile(nn_cam[qf == 'CMU'], q):.1f}, "
              f"body {np.percentile(nn_body[qf == 'CMU'], q):.1f} mm")
    for path in a.eval:
        per_scene = json.load(open(path))["by_condition"]["scene"]
        names = [r for r in np.unique(qr) if r in per_scene]
        net = np.array([per_scene[r]["mpjpe_root_mm"] for r in names])
        nn = np.array([nn_cam[qr == r].mean() for r in names])
        fl = np.array([floor[qr == r].mean() for r in names])
        print(f"{path}: {len(names)} recordings, the net's root-aligned MPJPE {net.mean():.1f} mm; per recording its "
              f"correlation with the lookup's distance {np.corrcoef(net, nn)[0, 1]:.2f}, with the floor "
              f"{np.corrcoef(net, fl)[0, 1]:.2f}; net / lookup {np.median(net / nn):.2f}, net / floor {np.median(net / fl):.2f} "
              f"(medians)")
    if a.poses:
        frames_against_lookup(a.poses, tc, tv)
    if a.shares:
        # Nested shares: each holds the one before it, so the curve is one draw growing.
        recs = np.random.default_rng(a.seed).permutation(np.unique(tr))
        for share in (16, 8, 4, 2, 1):
            n = max(1, len(recs) // share)
            pick = np.isin(tr, recs[:n])
            d = nn_cam if n == len(recs) else np.empty(len(qc))  # all of them: the lookup above
            for v in np.unique(qv) if n < len(recs) else []:
                sel, tsel = qv == v, pick & (tv == v)
                d[sel] = nearest_mpjpe(tc[tsel], qc[sel])[0] if tsel.any() else np.nan
            print(f"  the lookup from {n} of the {len(recs)} training recordings: {np.nanmean(d):.1f} mm")
    return 0


def frames_against_lookup(path, tc, tv):
    """The net's root-aligned error frame by frame beside each frame's lookup distance."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import refine_probe  # its reader of `yelan eval --poses`
    d = refine_probe.load(path)
    whole = d["valid"].all(axis=1)
    if not whole.any():
        sys.exit(f"{path}: no frame with all 13 joints valid")
    views = d["view"][whole]
    pred, truth = refine_probe.rooted(d["pred"][whole]), refine_probe.rooted(d["truth"][whole])
    net = np.linalg.norm(pred - truth, axis=2).mean(axis=1)
    nn = np.empty(len(truth))
    for view in np.unique(views):
        sel = views == view
        if not (tv == view).any():
            sys.exit(f"{path}: no training pose of the view '{view}' to look up")
        nn[sel] = nearest_mpjpe(tc[tv == view], truth[sel])[0]
    print(f"{path}: {len(net)} frames, the net {net.mean():.1f} mm root-aligned, the lookup {nn.mean():.1f}; "
          f"frame by frame correlation {np.corrcoef(net, nn)[0, 1]:.2f}")
    bins = np.digitize(nn, np.percentile(nn, [25, 50, 75]))
    for k in range(4):
        sel = bins == k
        print(f"  quartile {k + 1} of the lookup's distance: lookup {nn[sel].mean():.1f} mm, the net {net[sel].mean():.1f} mm")
    for view in np.unique(views):
        sel = views == view
        print(f"  {view}: lookup {nn[sel].mean():.1f} mm, the net {net[sel].mean():.1f} mm")


if __name__ == "__main__":
    sys.exit(main())
