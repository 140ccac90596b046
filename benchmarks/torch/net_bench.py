#!/usr/bin/python3
"""Times the PyTorch reference networks per frame, as `yelan bench networks` times ours.

usage: net_bench.py --reps N --threads 1,2 CONFIG:FRAMES ...
Prints one line per (config, mode, threads): "name mode threads ms_per_frame". Inference:
eval mode, both networks on a window of FRAMES. Training: train mode, forward, the losses
of weights_tools/reference/losses.py, backward. Runs under Debian's /usr/bin/python3."""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))


def median_seconds(fn, reps):
    fn()
    runs = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - t0)
    runs.sort()
    return runs[len(runs) // 2]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--reps", type=int, default=2)
    p.add_argument("--threads", default="1")
    p.add_argument("configs", nargs="+")
    a = p.parse_args()
    import torch
    from weights_tools.reference import MaskNet, PoseNet
    from weights_tools.reference.config import load_config
    from weights_tools.reference.losses import hpe_loss, mask_loss
    for item in a.configs:
        name, frames = item.rsplit(":", 1)
        frames = int(frames)
        cfg = load_config(name)
        mask, pose = MaskNet(cfg), PoseNet(cfg)
        x = torch.rand((frames, cfg.channels, cfg.height, cfg.width))
        target = torch.full((frames, cfg.joints, 3), 0.1)
        valid = torch.ones((frames, cfg.joints))
        labels = torch.zeros((frames, cfg.n_masks, cfg.height, cfg.width))
        for t in (int(v) for v in a.threads.split(",")):
            torch.set_num_threads(t)
            mask.eval()
            pose.eval()

            def infer():
                with torch.no_grad():
                    mask(x)
                    pose(x)
            s = median_seconds(infer, a.reps)
            print(f"{cfg.name} inference {t} {1e3 * s / frames:.4f}", flush=True)
            mask.train()
            pose.train()

            def train():
                m, sc = mask(x)
                mask_loss(m, sc, labels)[0].backward()
                hm, _ = pose(x)
                hpe_loss(hm, target, valid)[0].backward()
            s = median_seconds(train, a.reps)
            print(f"{cfg.name} training {t} {1e3 * s / frames:.4f}", flush=True)


if __name__ == "__main__":
    main()
