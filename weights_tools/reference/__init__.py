"""PyTorch re-implementation of YeLan's two networks (mask U-Net, pose net).

Module attribute names are chosen so that state_dict keys and shapes equal those of the
public reference code (miracleyoo/yelan-dynamic-dvs-hpe); see weights_tools/README.md.
"""
from .config import ModelConfig, load_config, CONFIG_DIR
from .mask_net import MaskNet
from .pose_net import PoseNet
from .dsnt import dsnt, joints_from_heatmaps

__all__ = ["ModelConfig", "load_config", "CONFIG_DIR", "MaskNet", "PoseNet", "dsnt",
           "joints_from_heatmaps", "build_networks", "load_networks", "case_networks"]


def build_networks(cfg):
    """Both networks of a config, in eval mode, with PyTorch's default initialisation."""
    return MaskNet(cfg).eval(), PoseNet(cfg).eval()


def load_networks(cfg, groups):
    """Both networks of a config holding the tensors of one of our weights files (the groups
    read_weights returns), num_batches_tracked as the int64 PyTorch keeps it:
    {"mask": MaskNet, "pose": PoseNet}, in training mode."""
    import numpy as np
    import torch
    nets = {"mask": MaskNet(cfg), "pose": PoseNet(cfg)}
    for g, net in nets.items():
        sd = {k: torch.from_numpy(np.array(v)) for k, v in groups[g].items()}
        for k in sd:
            if k.endswith("num_batches_tracked"):
                sd[k] = sd[k].to(torch.int64)
        net.load_state_dict(sd)
    return nets


def case_networks(weights, training, double=False):
    """What a parity case maker starts from: (cfg, {"mask": MaskNet, "pose": PoseNet}) of our
    weights file, on one thread (PyTorch's reductions then run in a fixed order), in training
    or eval mode, in float64 where asked (a yardstick for float32's own error)."""
    import torch
    from weights_tools.h5weights import read_weights
    from .config import config_from_dict
    torch.set_num_threads(1)
    cfg_dict, groups = read_weights(weights)
    cfg = config_from_dict(cfg_dict, weights)
    nets = load_networks(cfg, groups)
    for net in nets.values():
        net.train(training)
        if double:
            net.double()
    return cfg, nets
