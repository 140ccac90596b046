#!/usr/bin/python3
"""Times PyTorch training steps on the batches `yelan bench train` wrote, as it times ours.

usage: train_bench.py --data BATCHES.h5 --weights W.h5 --stages pose,mask --threads 1,2
                      --steps N [--warmup 2]
The config is the one stored in the weights file (the initial weights of our run). Per
stage and thread count: the trained network loaded from W, train mode, torch.optim.Adam
with our AdamOptions defaults (lr 1e-3, betas 0.9/0.999, eps 1e-8, L2 weight decay 1e-5);
each step is zero_grad, forward, the loss of weights_tools/reference/losses.py, backward,
step, cycling over the batches; WARMUP untimed steps, then the median of N. Prints one
line each: "train STAGE THREADS MS_PER_STEP INITIAL_LOSS" (the loss of the first step,
before any update). Runs under Debian's /usr/bin/python3."""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def load_net(stage, cfg, groups, torch):
    from weights_tools.reference import load_networks
    return load_networks(cfg, groups)[stage].train()


def run(stage, cfg, groups, batches, threads, steps, warmup, torch):
    from weights_tools.reference.losses import hpe_loss, mask_loss
    torch.set_num_threads(threads)
    net = load_net(stage, cfg, groups, torch)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3, betas=(0.9, 0.999), eps=1e-8, weight_decay=1e-5)

    def step(k):
        b = batches[k % len(batches)]
        opt.zero_grad()
        if stage == "pose":
            x = b["input"]
            heatmaps, _ = net(x.reshape(-1, cfg.window, *x.shape[1:]))  # windows x S frames
            loss = hpe_loss(heatmaps, b["target"], b["valid"])[0]
        else:
            masks, scores = net(b["input"])
            loss = mask_loss(masks, scores, b["labels"])[0]
        loss.backward()
        opt.step()
        return float(loss)

    first = step(0)
    for k in range(1, warmup):
        step(k)
    runs = []
    for i in range(steps):
        t0 = time.perf_counter()
        step(warmup + i)
        runs.append(time.perf_counter() - t0)
    runs.sort()
    return 1e3 * runs[len(runs) // 2], first


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True)
    p.add_argument("--weights", required=True)
    p.add_argument("--stages", default="pose,mask")
    p.add_argument("--threads", default="1")
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--warmup", type=int, default=2)
    a = p.parse_args(argv)
    torch = require_torch()
    import h5py
    from weights_tools.h5weights import read_weights
    from weights_tools.reference.config import config_from_dict

    cfg_dict, groups = read_weights(a.weights)
    cfg = config_from_dict(cfg_dict, a.weights)
    with h5py.File(a.data, "r") as f:
        data = {}
        for stage in a.stages.split(","):
            if stage not in f:
                sys.stderr.write(f"train_bench: {a.data} has no group /{stage}\n")
                return 2
            g = f[stage]
            names = ("input", "target", "valid") if stage == "pose" else ("input", "labels")
            n = g["input"].shape[0]
            data[stage] = [{k: torch.from_numpy(g[k][i]) for k in names} for i in range(n)]
    for stage, batches in data.items():
        for t in (int(v) for v in a.threads.split(",")):
            ms, first = run(stage, cfg, groups, batches, t, a.steps, a.warmup, torch)
            print(f"train {stage} {t} {ms:.4f} {first:.9g}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
