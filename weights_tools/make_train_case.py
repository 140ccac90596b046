#!/usr/bin/python3
"""A training parity case: both networks trained for STEPS steps with Adam (lr 1e-3, L2
weight decay 1e-5, batch statistics) from a weights file, on seeded random batches.

Writes OUT (HDF5): per step i, group step{i} with input (S,C,H,W), target (S,J,3), valid
(S,J), labels (S,N,H,W); datasets loss_mask and loss_pose (STEPS,), the losses before each
update. The C++ test replays the same batches and compares its losses."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.atomic import atomic_path  # noqa: E402
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weights", required=True, help="our HDF5 weights (its config is used)")
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--seed", type=int, required=True)
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--double", action="store_true",
                   help="train in float64 (a yardstick: how far float32 training itself drifts)")
    a = p.parse_args(argv)
    torch = require_torch()
    import h5py
    import numpy as np
    from weights_tools.reference import case_networks
    from weights_tools.reference.losses import hpe_loss, mask_loss

    cfg, nets = case_networks(a.weights, training=True, double=a.double)
    opts = {g: torch.optim.Adam(net.parameters(), lr=1e-3, weight_decay=1e-5) for g, net in nets.items()}
    gen = torch.Generator().manual_seed(a.seed)
    S, J = cfg.window, cfg.joints
    losses = {"mask": [], "pose": []}
    with atomic_path(a.output) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = "yelan-train-case"
            for i in range(a.steps):
                x = torch.rand((S, cfg.channels, cfg.height, cfg.width), generator=gen)
                target = 1.6 * torch.rand((S, J, 3), generator=gen) - 0.8
                valid = (torch.rand((S, J), generator=gen) > 0.2).float()
                labels = (torch.rand((S, cfg.n_masks, cfg.height, cfg.width), generator=gen) > 0.7).float()
                g = f.create_group(f"step{i}", track_order=True)
                for name, t in (("input", x), ("target", target), ("valid", valid), ("labels", labels)):
                    g.create_dataset(name, data=t.numpy().astype(np.float32), track_times=False)
                dt = torch.float64 if a.double else torch.float32
                opts["mask"].zero_grad()
                masks, scores = nets["mask"](x.to(dt))
                lm = mask_loss(masks, scores, labels.to(dt))[0]
                lm.backward()
                opts["mask"].step()
                opts["pose"].zero_grad()
                heatmaps, _ = nets["pose"](x.to(dt))
                lp = hpe_loss(heatmaps, target.to(dt), valid.to(dt))[0]
                lp.backward()
                opts["pose"].step()
                losses["mask"].append(float(lm))
                losses["pose"].append(float(lp))
            for k, v in losses.items():
                f.create_dataset("loss_" + k, data=np.array(v, dtype=np.float64), track_times=False)
    print(f"wrote {a.output}: {a.steps} steps, loss_mask {losses['mask'][0]:.6g} -> {losses['mask'][-1]:.6g}, "
          f"loss_pose {losses['pose'][0]:.6g} -> {losses['pose'][-1]:.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
