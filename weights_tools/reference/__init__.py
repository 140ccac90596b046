"""PyTorch re-implementation of YeLan's two networks (mask U-Net, pose net).

Module attribute names are chosen so that state_dict keys and shapes equal those of the
public reference code (miracleyoo/yelan-dynamic-dvs-hpe); see weights_tools/README.md.
"""
from .config import ModelConfig, load_config, CONFIG_DIR
from .mask_net import MaskNet
from .pose_net import PoseNet
from .dsnt import dsnt, joints_from_heatmaps

__all__ = ["ModelConfig", "load_config", "CONFIG_DIR", "MaskNet", "PoseNet", "dsnt",
           "joints_from_heatmaps", "build_networks"]


def build_networks(cfg):
    """Both networks of a config, in eval mode, with PyTorch's default initialisation."""
    return MaskNet(cfg).eval(), PoseNet(cfg).eval()
