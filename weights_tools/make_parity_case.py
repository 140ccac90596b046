#!/usr/bin/python3
"""A parity case for the C++ networks: random weights, a random window, every head's output.

Writes OUT (HDF5): input (S,C,H,W); masks (S,N,H,W) U-Net logits; scores (S,N) sigmoid
scores; heatmaps/stage{i}/{xy,zy,xz} (S,J,h,w) softmax maps; joints_norm (S,J,3) DSNT of
the last stage; root attributes config, seed, weights_file. And the weights file beside it
(--weights, default OUT with .h5 replaced by .weights.h5). The pose net sees `input` as is
(no mask applied): both networks are checked on their own."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.atomic import atomic_path  # noqa: E402
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def randomise_batchnorm(net, calib_input, gen):
    """Non-trivial BN state that still keeps activations near unit scale (so outputs depend
    on the input, and a C++ BN ignoring any of its four tensors fails parity): running
    statistics measured on a calibration input, then perturbed; random affine parameters."""
    import torch
    bns = [m for m in net.modules() if isinstance(m, torch.nn.BatchNorm2d)]
    for m in bns:
        m.momentum = 1.0  # running stats := this batch's
    net.train()
    with torch.no_grad():
        net(calib_input)
        for m in bns:
            n = m.num_features
            std = m.running_var.sqrt()
            m.running_mean.add_(0.2 * std * torch.randn(n, generator=gen))
            m.running_var.mul_(0.5 + torch.rand(n, generator=gen))
            m.weight.copy_(0.75 + 0.5 * torch.rand(n, generator=gen))
            m.bias.copy_(0.2 * (torch.rand(n, generator=gen) - 0.5))
            m.num_batches_tracked.fill_(int(torch.randint(1, 10000, (1,), generator=gen)))
            m.momentum = 0.1
    net.eval()


def soften_heatmaps(pose_net, x, target_std=1.5):
    """Random nets give heatmap logits with a std of ~10, so every softmax is one-hot and
    insensitive to errors. Scaling each hourglass' last BN pair brings them near target_std."""
    import torch
    stds = {}
    hooks = [hg.register_forward_hook(lambda m, i, o, key=id(hg): stds.__setitem__(key, o.std()))
             for plane in (pose_net.xy_hm_cnns, pose_net.zy_hm_cnns, pose_net.xz_hm_cnns)
             for hg in plane]
    for stage in range(pose_net.cfg.stages):
        with torch.no_grad():
            pose_net(x)
            for plane in (pose_net.xy_hm_cnns, pose_net.zy_hm_cnns, pose_net.xz_hm_cnns):
                last = plane[stage].up_layers[-1]
                k = target_std / float(stds[id(plane[stage])])
                for bn in (last.module[4], last.shortcut[1]):
                    bn.weight.mul_(k)
                    bn.bias.mul_(k)
    for h in hooks:
        h.remove()


def build_case(cfg, seed):
    """-> (mask_net, pose_net, input, outputs dict)."""
    import torch
    from weights_tools.reference import MaskNet, PoseNet
    torch.manual_seed(seed)
    mask_net, pose_net = MaskNet(cfg), PoseNet(cfg)
    gen = torch.Generator().manual_seed(seed + 1)
    shape = (cfg.window, cfg.channels, cfg.height, cfg.width)
    # pose.outside_input: stage 2 reads twice the channels; stage 1 the first half of `input`.
    pose_shape = (cfg.window, 2 * cfg.channels if cfg.outside_input else cfg.channels, cfg.height, cfg.width)
    randomise_batchnorm(mask_net, torch.rand(shape, generator=gen), gen)
    calib = torch.rand(pose_shape, generator=gen)
    randomise_batchnorm(pose_net, calib, gen)
    soften_heatmaps(pose_net, calib)
    x = torch.rand(pose_shape, generator=gen)
    with torch.no_grad():
        masks, scores = mask_net(x[:, :cfg.channels])
        heatmaps, joints = pose_net(x)
    out = {"masks": masks, "scores": scores, "joints_norm": joints}
    for i, planes in enumerate(heatmaps):
        for name, hm in zip(("xy", "zy", "xz"), planes):
            out[f"heatmaps/stage{i}/{name}"] = hm
    return mask_net, pose_net, x, out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--config", required=True, help="config name or JSON file")
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("--weights", help="weights file to write (default: OUT stem + .weights.h5)")
    p.add_argument("-o", "--output", required=True, help="parity case .h5")
    a = p.parse_args(argv)
    torch = require_torch()
    import h5py
    import numpy as np
    from weights_tools.reference.config import ConfigError, load_config
    from weights_tools.h5weights import to_float32, write_weights
    try:
        cfg = load_config(a.config)
    except ConfigError as e:
        sys.stderr.write(f"make_parity_case: error: {e}\n")
        return 2
    torch.set_num_threads(1)
    mask_net, pose_net, x, out = build_case(cfg, a.seed)
    weights = a.weights or (a.output[:-3] if a.output.endswith(".h5") else a.output) + ".weights.h5"
    write_weights(weights, cfg.to_json(), {
        g: {k: to_float32(k, v, "parity") for k, v in n.state_dict().items()}
        for g, n in (("mask", mask_net), ("pose", pose_net))})
    with atomic_path(a.output) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = "yelan-parity-case"
            f.attrs["version"] = np.int64(1)
            f.attrs["config"] = cfg.to_json()
            f.attrs["seed"] = np.int64(a.seed)
            f.attrs["weights_file"] = os.path.basename(weights)
            f.attrs["masks"] = "U-Net logits (before sigmoid)"
            f.create_dataset("input", data=x.numpy(), track_times=False)
            for name, t in out.items():
                f.create_dataset(name, data=t.numpy().astype(np.float32), track_times=False)
    print(f"wrote {a.output} and {weights}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
