#!/usr/bin/env python3
"""Would a small MLP over stage 2's output place the joints better? A probe outside the engine
(PyTorch): it reads the frames `yelan eval --poses CSV` scored (the prediction under the true
head depth and the label), learns from one CSV the map from a predicted pose (relative to its
hip centre) to the true one (relative to the true hip centre), and scores it on another CSV
against the net's own poses and the per-view mean pose, root-aligned (the figure issue 15 asks
under 100 mm) and with the predicted hip kept (the paper protocol's MPJPE).

    /usr/bin/python3 refine_probe.py TRAIN.csv VAL.csv [--context K] [--inputs xyz|xy]
                     [--epochs 40] [--hidden 512] [--seed 1] [--space mm|norm] [--sensor 346x260]
                     [--save OUT.npz]

TRAIN.csv must be the net's poses on recordings it never trained on: a refiner fitted to
poses the net memorised learns errors it will not meet. --context K: the K latest frames of
the same recording (50 per second, the oldest repeated at its start) side by side, causal
as `yelan run` would have them (a gap in time or another recording starts a new run of frames).
--inputs xy: only the predicted image positions (scaled to the
hip's depth), as lift_probe.py's lifter, not the net's depths. --space norm: the MLP reads and
writes the net's own normalised coordinates (SPEC section 6, with each frame's true head depth
and the sensor's size from the CSV, or --sensor for CSVs without it), as an engine's refiner
would before any depth estimate; mm: camera millimetres relative to the hips. Frames whose hips are both in
the picture; joints out of it (validJ 0) are left out of the loss and the scores.
"""
import argparse
import csv
import sys

import numpy as np

VIEWS = ("front", "back", "left", "right")
HIPS = (5, 6)
HANDS = (7, 8)


def load(path):
    """-> dict: source (list), view, t (us), pred and truth (N x 13 x 3, mm), valid (N x 13),
    cam (N x 7: fx, fy, cx, cy, true head depth, sensor width and height), sorted by source
    and time; frames whose hips are not both in the picture are left out."""
    src, view, t, pred, truth, valid, cam = [], [], [], [], [], [], []
    with open(path, newline="") as f:
        rows = csv.reader(f)
        head = next(rows)
        if head[:4] != ["source", "view", "window", "frame"]:
            sys.exit(f"{path}: not the CSV of yelan eval --poses (header {head[:4]})")
        for r in rows:
            if len(r) != len(head):
                sys.exit(f"{path}: a row of {len(r)} fields, the header has {len(head)}")
            ok = [v == "1" for v in r[88:101]]
            if not (ok[HIPS[0]] and ok[HIPS[1]]):
                continue
            valid.append(ok)
            src.append(r[0])
            view.append(r[1])
            t.append(int(r[4]))
            size = [float(v) for v in r[101:103]] if len(r) >= 103 else SENSOR
            cam.append([float(v) for v in r[5:10]] + size)
            v = np.array(r[10:88], dtype=np.float64)
            pred.append(v[:39].reshape(13, 3))
            truth.append(v[39:].reshape(13, 3))
    order = sorted(range(len(src)), key=lambda i: (src[i], t[i]))
    pick = lambda a: [a[i] for i in order]
    return {"source": pick(src), "view": np.array(pick(view)), "t": np.array(pick(t)),
            "pred": np.array(pick(pred)), "truth": np.array(pick(truth)),
            "valid": np.array(pick(valid)), "cam": np.array(pick(cam))}


SENSOR = [346, 260]


def normalise(p, cam):
    """Camera mm -> the net's normalised coordinates (engine/train/pose_norm.cpp)."""
    fx, fy, cx, cy, zr, w, h = (cam[:, None, i] for i in range(7))
    u, v = fx * p[..., 0] / p[..., 2] + cx, fy * p[..., 1] / p[..., 2] + cy
    s = zr * np.maximum(w / fx, h / fy)
    r = np.sqrt(zr * zr + s * s)
    return np.stack([(u - w / 2) / (w / 2), (v - h / 2) / (h / 2), (r + zr) / s * (1 - zr / p[..., 2])], axis=-1)


def denormalise(n, cam):
    fx, fy, cx, cy, zr, w, h = (cam[:, None, i] for i in range(7))
    s = zr * np.maximum(w / fx, h / fy)
    r = np.sqrt(zr * zr + s * s)
    z = zr / (1 - n[..., 2] * s / (r + zr))
    u, v = n[..., 0] * (w / 2) + w / 2, n[..., 1] * (h / 2) + h / 2
    return np.stack([(u - cx) * z / fx, (v - cy) * z / fy, z], axis=-1)


def rooted(p):
    return p - p[:, HIPS, :].mean(axis=1, keepdims=True)


def image_features(d):
    """Each frame's predicted image positions scaled to its hip's depth, relative to the hip,
    in metres: the 2D skeleton without the net's depths (--inputs xy)."""
    p = d["pred"]
    hip = p[:, HIPS, :].mean(axis=1)
    xy = p[..., :2] / p[..., 2:3] * hip[:, None, 2:3] - hip[:, None, :2]
    return xy.reshape(len(p), 26) / 1000


FRAME_US = 20000  # the evaluation's frames, 50 a second


def with_context(x, d, k):
    """The k latest frames of the same run of frames side by side (the oldest repeated): a row
    continues the one before it only if it is the same recording one frame period later."""
    if k <= 1:
        return x
    prev = np.arange(len(x))
    cols = [x]
    same = np.array([i > 0 and d["source"][i] == d["source"][i - 1] and d["t"][i] - d["t"][i - 1] == FRAME_US
                     for i in range(len(x))])
    for _ in range(k - 1):
        prev = np.where(same[prev], prev - 1, prev)
        cols.append(x[prev])
    return np.concatenate(cols, axis=1)


def mpjpe(a, b, valid):
    return np.linalg.norm(a - b, axis=2)[valid].mean()


def report(name, pose_root, d):
    truth, ok = rooted(d["truth"]), d["valid"]
    e = np.linalg.norm(pose_root - truth, axis=2)
    views = " / ".join(f"{e[(d['view'] == v)[:, None] & ok].mean():.1f}" if (d["view"] == v).any() else "-" for v in VIEWS)
    depth = np.abs(pose_root[..., 2] - truth[..., 2])[ok].mean()
    hands = e[:, HANDS][ok[:, HANDS]].mean()
    print(f"  {name:<28} root-aligned {e[ok].mean():6.1f} mm  hands {hands:6.1f}  "
          f"depth {depth:5.1f}  {' / '.join(VIEWS)} {views}")
    return e[ok].mean()


def mlp(inputs, outputs, hidden):
    """Two hidden ReLU layers with dropout 0.1 (this probe's and lift_probe.py's)."""
    import torch
    return torch.nn.Sequential(torch.nn.Linear(inputs, hidden), torch.nn.ReLU(), torch.nn.Dropout(0.1),
                               torch.nn.Linear(hidden, hidden), torch.nn.ReLU(), torch.nn.Dropout(0.1),
                               torch.nn.Linear(hidden, outputs))


def fit(net, n, batch_loss, epochs, on_report, weight_decay=0.0):
    """Adam at 1e-3 annealed to 0 by a cosine over `epochs`, batches of 256 drawn afresh each
    epoch (batch_loss(indices) -> loss); on_report(epoch, last loss) after every tenth epoch and
    the last, the net in eval mode."""
    import torch
    if n == 0:
        sys.exit("no training frames")
    opt = torch.optim.Adam(net.parameters(), 1e-3, weight_decay=weight_decay)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, epochs)
    for epoch in range(epochs):
        net.train()
        perm = torch.randperm(n)
        for i in range(0, n, 256):
            loss = batch_loss(perm[i:i + 256])
            opt.zero_grad()
            loss.backward()
            opt.step()
        sched.step()
        if epoch % 10 == 9 or epoch == epochs - 1:
            net.eval()
            on_report(epoch, loss.item())


def main(argv):
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("train")
    a.add_argument("val")
    a.add_argument("--context", type=int, default=1)
    a.add_argument("--inputs", choices=("xyz", "xy"), default="xyz")
    a.add_argument("--epochs", type=int, default=40)
    a.add_argument("--hidden", type=int, default=512)
    a.add_argument("--seed", type=int, default=1)
    a.add_argument("--space", choices=("mm", "norm"), default="mm")
    a.add_argument("--sensor", default="346x260")
    a.add_argument("--save", help="the validation's refined poses (npz: source, t, refined, truth, pred)")
    o = a.parse_args(argv)
    import torch
    torch.set_num_threads(2)
    torch.manual_seed(o.seed)
    SENSOR[:] = [int(v) for v in o.sensor.split("x")]
    tr, va = load(o.train), load(o.val)
    if o.space == "norm" and o.inputs == "xy":
        sys.exit("--inputs xy reads image positions in mm at the hip's depth: give --space mm")
    print(f"train {len(tr['pred'])} frames of {len(set(tr['source']))} recordings, "
          f"val {len(va['pred'])} of {len(set(va['source']))}; inputs {o.inputs}, context {o.context}")
    # What the MLP reads and writes: poses relative to their hip centre, in metres (mm) or in
    # the net's normalised units (norm); `back` turns an output into root-relative camera mm.
    if o.space == "norm":
        enc = lambda d, p: rooted(normalise(p, d["cam"])).reshape(-1, 39)
        def back(d, q):
            hip = normalise(d["pred"], d["cam"])[:, HIPS, :].mean(axis=1, keepdims=True)
            return rooted(denormalise(q.reshape(-1, 13, 3) + hip, d["cam"]))
    else:
        enc = lambda d, p: rooted(p).reshape(-1, 39) / 1000
        back = lambda d, q: q.reshape(-1, 13, 3) * 1000
    xt = with_context(image_features(tr) if o.inputs == "xy" else enc(tr, tr["pred"]), tr, o.context)
    xv = with_context(image_features(va) if o.inputs == "xy" else enc(va, va["pred"]), va, o.context)
    yt = enc(tr, tr["truth"])
    # The net's own pose is the starting point the MLP corrects (xyz inputs): a residual.
    base_t = enc(tr, tr["pred"]) if o.inputs == "xyz" else np.zeros_like(yt)
    base_v = enc(va, va["pred"]) if o.inputs == "xyz" else np.zeros((len(xv), 39))
    floor = np.zeros((len(xv), 13, 3))
    truth_t = rooted(tr["truth"])
    def mean_pose(sel):  # over the frames where each joint is in the picture
        w = tr["valid"][sel][..., None]
        return (truth_t[sel] * w).sum(axis=0) / np.maximum(w.sum(axis=0), 1)
    for v in VIEWS:
        if (va["view"] == v).any():
            floor[va["view"] == v] = mean_pose(tr["view"] == v if (tr["view"] == v).any() else slice(None))
    net = mlp(xt.shape[1], 39, o.hidden)
    T = lambda v: torch.tensor(v, dtype=torch.float32)
    X, Y, B, Xv, V = T(xt), T(yt), T(base_t), T(xv), T(tr["valid"])
    refine = lambda x, b: b + net(x)
    result = {}

    def scored(epoch, loss):
        with torch.no_grad():
            result["r"] = back(va, refine(Xv, T(base_v)).numpy().astype(np.float64))
        print(f"epoch {epoch + 1}: train loss {loss:.4f}, val root-aligned "
              f"{mpjpe(result['r'], rooted(va['truth']), va['valid']):.1f} mm")
    fit(net, len(X), lambda b: ((refine(X[b], B[b]) - Y[b]).view(-1, 13, 3).norm(dim=2) * V[b]).sum() / V[b].sum(),
        o.epochs, scored, weight_decay=1e-5)
    r = result["r"]
    print("validation (frames with both hips in the picture, joints in it):")
    report("per-view mean pose (floor)", floor, va)
    net_e = report("the net", rooted(va["pred"]), va)
    ref_e = report("refined", r, va)
    hip_pred = va["pred"][:, HIPS, :].mean(axis=1, keepdims=True)
    print(f"  paper protocol (the net's hip kept): the net {mpjpe(va['pred'], va['truth'], va['valid']):.1f} mm, "
          f"refined {mpjpe(r + hip_pred, va['truth'], va['valid']):.1f} mm")
    print(f"  refined against the net: {ref_e - net_e:+.1f} mm root-aligned ({100 * (ref_e / net_e - 1):+.1f}%)")
    with torch.no_grad():
        rt = back(tr, refine(X, B).numpy().astype(np.float64))
    print(f"training frames: the net {mpjpe(rooted(tr['pred']), rooted(tr['truth']), tr['valid']):.1f} mm root-aligned, "
          f"refined {mpjpe(rt, rooted(tr['truth']), tr['valid']):.1f}")
    if o.save:
        np.savez_compressed(o.save, source=np.array(va["source"]), t=va["t"], refined=r, truth=va["truth"], pred=va["pred"])


if __name__ == "__main__":
    main(sys.argv[1:])
