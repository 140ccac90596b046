#!/usr/bin/python3
"""The streaming pipeline's network work per tick in PyTorch 1.13, as `yelan bench run` runs
ours: stage 1 (the U-Net on one frame) on the given share of ticks (our early exit's), the
mask applied, and stage 2 on one frame per tick (causal configs: one ConvLSTM step) or on a
window every S ticks (bidirectional configs). TORE read-out is not PyTorch's work and is
left out of both sides' comparison figure.

usage: pipeline_bench.py --weights W --threads T --mask-fraction F [--ticks 60]
Prints "ms_per_tick X" and "poses_per_s Y". Runs under Debian's /usr/bin/python3."""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--weights", required=True)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--mask-fraction", type=float, default=1.0)
    p.add_argument("--ticks", type=int, default=60)
    a = p.parse_args()
    import torch
    from weights_tools.h5weights import read_weights
    from weights_tools.reference import MaskNet, PoseNet
    from weights_tools.reference.config import config_from_dict
    torch.set_num_threads(a.threads)
    cfg_dict, _ = read_weights(a.weights)  # the config only: timing does not depend on the values
    cfg = config_from_dict(cfg_dict, a.weights)
    mask, pose = MaskNet(cfg).eval(), PoseNet(cfg).eval()
    frame = torch.rand((1, cfg.channels, cfg.height, cfg.width))
    window = torch.rand((1, cfg.window, cfg.channels, cfg.height, cfg.width))
    keep = torch.ones((1, 1, cfg.height, cfg.width))
    causal = cfg.convlstm != "bidirectional"

    def tick(i, owed):
        owed += a.mask_fraction
        if owed >= 1.0 or i == 0:  # stage 1 on the same share of ticks as ours
            owed = max(0.0, owed - 1.0)
            if cfg.masked_input:
                m, _ = mask(frame)
                keep.copy_((m[:, :1] > 0).float())
        x = frame * keep
        if causal:
            pose(x.unsqueeze(0))
        elif (i + 1) % cfg.window == 0:
            pose(window)
        return owed

    with torch.no_grad():
        owed = 0.0
        for i in range(cfg.window):  # warm-up
            owed = tick(i, owed)
        times = []
        owed = 0.0
        for i in range(a.ticks):
            t0 = time.perf_counter()
            owed = tick(i, owed)
            times.append(time.perf_counter() - t0)
    ms = 1e3 * sum(times) / len(times)
    print(f"ms_per_tick {ms:.4f}")
    print(f"poses_per_s {1e3 / ms:.4f}")


if __name__ == "__main__":
    main()
