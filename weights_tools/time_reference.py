#!/usr/bin/python3
"""Forward time of the PyTorch reference networks: pose net per window of S frames and
mask net per frame, in eval mode, no autograd, on --threads threads (default 1)."""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def best_of(fn, reps):
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), times


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--config", default="paper")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--reps", type=int, default=2)
    p.add_argument("--mask-frames", type=int, default=1, help="frames per mask-net call")
    a = p.parse_args(argv)
    torch = require_torch()
    from weights_tools.reference import build_networks, load_config
    torch.set_num_threads(a.threads)
    cfg = load_config(a.config)
    mask, pose = build_networks(cfg)
    window = torch.rand(cfg.window, cfg.channels, cfg.height, cfg.width)
    frames = window[: a.mask_frames]
    with torch.no_grad():
        pose_best, pose_all = best_of(lambda: pose(window), a.reps)
        mask_best, mask_all = best_of(lambda: mask(frames), a.reps)
    print(f"config {cfg.name}: input {cfg.channels}x{cfg.height}x{cfg.width}, S={cfg.window}, "
          f"torch {torch.__version__}, {torch.get_num_threads()} thread(s), load {os.getloadavg()[0]:.2f}")
    print(f"pose net: {pose_best:.3f} s per window of {cfg.window} frames "
          f"({1000 * pose_best / cfg.window:.1f} ms/frame); runs {[round(t, 3) for t in pose_all]}")
    print(f"mask net: {mask_best / a.mask_frames:.3f} s per frame; runs "
          f"{[round(t, 3) for t in mask_all]} for {a.mask_frames} frame(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
