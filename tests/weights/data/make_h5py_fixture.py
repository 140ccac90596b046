#!/usr/bin/python3
"""Writes h5py_written.h5: a few tensors as weights_tools/h5weights.py (h5py) writes them,
so the C++ reader is tested on h5py's own encoding (variable-length UTF-8 string attributes,
numpy int64 version). Values are chosen so the test can state them."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
import numpy as np  # noqa: E402
from weights_tools.h5weights import write_weights  # noqa: E402

groups = {
    "mask": {"fc.bias": np.array([0.5, -1.25, 3.0, 1e-7], dtype=np.float32)},
    "pose": {
        "in_cnn.0.weight": np.arange(2 * 1 * 3 * 3, dtype=np.float32).reshape(2, 1, 3, 3) / 8,
        "in_cnn.1.num_batches_tracked": np.array(16777216, dtype=np.float32),
    },
}
config = '{"name":"fixture","note":"caf\\u00e9 \\"quoted\\""}'
write_weights(os.path.join(os.path.dirname(os.path.abspath(__file__)), "h5py_written.h5"), config, groups)
