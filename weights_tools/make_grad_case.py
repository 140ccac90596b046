#!/usr/bin/python3
"""A gradient parity case: the losses of both networks in training mode (batch statistics)
and every parameter's gradient, from a weights file and a seeded random batch.

Writes OUT (HDF5): input (S,C,H,W), target (S,J,3), valid (S,J), labels (S,N,H,W);
attributes loss_mask, loss_pose, loss_pose_stage{i}; groups grad_mask/<key>, grad_pose/<key>
(dL/dparam) and after_mask/<key>, after_pose/<key> (BN buffers after the forward).
Runs only under Debian's /usr/bin/python3 (python3-torch 1.13)."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.atomic import atomic_path  # noqa: E402
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weights", required=True, help="our HDF5 weights (its config is used)")
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--eval", action="store_true", help="BN with running statistics (default: batch statistics)")
    p.add_argument("--double", action="store_true",
                   help="compute in float64 (a yardstick: how far float32 itself is from exact)")
    a = p.parse_args(argv)
    torch = require_torch()
    import h5py
    import numpy as np
    from weights_tools.reference import case_networks
    from weights_tools.reference.losses import hpe_loss, mask_loss

    cfg, nets = case_networks(a.weights, training=not a.eval, double=a.double)
    gen = torch.Generator().manual_seed(a.seed)
    S, J = cfg.window, cfg.joints
    x = torch.rand((S, cfg.channels, cfg.height, cfg.width), generator=gen)
    target = 1.6 * torch.rand((S, J, 3), generator=gen) - 0.8
    valid = (torch.rand((S, J), generator=gen) > 0.2).float()
    labels = (torch.rand((S, cfg.n_masks, cfg.height, cfg.width), generator=gen) > 0.7).float()

    dt = torch.float64 if a.double else torch.float32
    masks, scores = nets["mask"](x.to(dt))
    lm, first, full, mse = mask_loss(masks, scores, labels.to(dt))
    lm.backward()
    heatmaps, _ = nets["pose"](x.to(dt))
    lp, stages = hpe_loss(heatmaps, target.to(dt), valid.to(dt))
    lp.backward()

    # Written like make_parity_case.py's file on purpose (one dataset per tensor, no
    # timestamps, so a case file is byte-reproducible); the two carry different tensors.
    with atomic_path(a.output) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = "yelan-grad-case"
            f.attrs["loss_mask"] = float(lm)
            f.attrs["loss_mask_parts"] = np.array([float(first), float(full), float(mse)])
            f.attrs["loss_pose"] = float(lp)
            for i, s in enumerate(stages):
                f.attrs[f"loss_pose_stage{i}"] = float(s)
            for name, t in (("input", x), ("target", target), ("valid", valid), ("labels", labels)):
                f.create_dataset(name, data=t.numpy().astype(np.float32), track_times=False)
            for g, net in nets.items():
                gg = f.create_group("grad_" + g, track_order=True)
                ga = f.create_group("after_" + g, track_order=True)
                for k, prm in net.named_parameters():
                    gg.create_dataset(k, data=prm.grad.numpy().astype(np.float32 if not a.double else np.float64), track_times=False)
                for k, buf in net.named_buffers():
                    ga.create_dataset(k, data=buf.numpy().astype(np.float32), track_times=False)
    print(f"wrote {a.output}: loss_mask {float(lm):.6g}, loss_pose {float(lp):.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
