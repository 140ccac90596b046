#!/usr/bin/python3
"""How much of a labelled recording's event stream is the dancer: per recording, the share of
events inside the true human mask (the masks are stored at 50 Hz; an event takes the mask
nearest its time) and the events per pixel and second on the mask against the rest of the
frame, after the first 0.5 s. A low-light dancer whose rate is the noise's is not in the
events at all (models/README.md, "Session 2026-11-27 (fourth)").
  /usr/bin/python3 benchmarks/training/dancer_share.py REC.yelan.h5 [...]
Needs Debian's python3-h5py and python3-numpy."""
import sys

import h5py
import numpy as np


def dancer_share(path, skip_us=500_000):
    with h5py.File(path, "r") as f:
        t, x, y = f["events/t"][:], f["events/x"][:], f["events/y"][:]
        mask_t, masks = f["masks/t"][:], f["masks/data"]
        h, w = masks.shape[1:]
        keep = t > skip_us
        t, x, y = t[keep], x[keep], y[keep]
        if len(t) < 2:
            raise ValueError(f"{path}: fewer than 2 events after {skip_us / 1e6} s")
        nearest = np.clip(np.searchsorted(mask_t, t), 0, len(mask_t) - 1)
        inside, covered = 0, []
        for k in np.unique(nearest):
            m = masks[k] != 0
            sel = nearest == k
            inside += int(m[y[sel], x[sel]].sum())
            covered.append(m.mean())
    seconds = (t[-1] - t[0]) / 1e6
    share = float(np.mean(covered))
    rate_in = inside / seconds / max(share * h * w, 1)
    rate_out = (len(t) - inside) / seconds / ((1 - share) * h * w)
    return inside / len(t), share, rate_in, rate_out


def main(paths):
    if not paths:
        sys.exit(__doc__)
    for p in paths:
        events_in, share, rate_in, rate_out = dancer_share(p)
        print(f"{p.split('/')[-1]}: events in the mask {events_in:.1%}, mask {share:.1%} of the frame, "
              f"events/s per pixel on the dancer {rate_in:.1f}, elsewhere {rate_out:.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
