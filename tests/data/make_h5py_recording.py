#!/usr/bin/python3
"""Writes h5py_recording.yelan.h5: a labelled recording laid out as SPEC 2 says, written with
h5py the ordinary way (variable-length UTF-8 string attributes, the sensor size only in
/camera/width and /camera/height), so the CLI is tested on a file another tool wrote (issue
17, rows 21-22). The content is a thinned 0.26 s of data/demo's recording: long enough for one
8-frame window after eval's 0.1 s warm-up, small enough to commit.
Run once from anywhere: /usr/bin/python3 tests/data/make_h5py_recording.py"""
import os

import h5py
import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
demo = os.path.join(here, "..", "..", "data", "demo", "lena-93_03-front-high-static.yelan.h5")
END_US, EVERY = 260_000, 200  # 14 masks, ~300 events

with h5py.File(demo, "r") as src, h5py.File(os.path.join(here, "h5py_recording.yelan.h5"), "w") as f:
    n = int(np.searchsorted(src["events/t"][:], END_US))
    for k in "txyp":
        f["events/" + k] = src["events/" + k][:n:EVERY]
    t = f["events/t"][:]
    f["events/ms_to_idx"] = np.searchsorted(t, np.arange(0, END_US // 1000 + 1) * 1000).astype(np.uint64)
    for k in ("K", "dist", "M", "width", "height"):
        f["camera/" + k] = src["camera/" + k][()]
    labels = np.flatnonzero(src["labels/t"][:] <= END_US)[::3]  # 100 Hz of the 300: a smaller file
    for k in ("t", "joints", "valid"):
        f["labels/" + k] = src["labels/" + k][labels]
    masks = src["masks/t"][:] <= END_US
    f["masks/t"] = src["masks/t"][masks]
    f.create_dataset("masks/data", data=src["masks/data"][masks], chunks=(1, 260, 346), compression="gzip",
                     compression_opts=9)
    f.attrs["format"] = "yelan-recording"
    f.attrs["version"] = 1
    for k in ("character", "motion", "view", "lighting", "background"):
        f.attrs[k] = src.attrs[k].decode()
