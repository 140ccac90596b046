#!/usr/bin/python3
"""Our HDF5 weights file -> PyTorch state_dict .pt (see README.md)."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Read our HDF5 weights file, check every tensor against the config stored "
        "in it, and save PyTorch state_dicts (num_batches_tracked back to int64).",
        epilog="Default output: a dict {format: 'yelan-state-dicts', version: 1, config: "
        "<JSON string>, mask: state_dict, pose: state_dict}, which export_h5.py reads back. "
        "--group mask|pose saves that network's bare state_dict instead.")
    p.add_argument("weights", help="our .h5 weights file")
    p.add_argument("--group", choices=("mask", "pose"), help="save only this network's state_dict")
    p.add_argument("-o", "--output", required=True, help="output .pt (written atomically)")
    return p.parse_args(argv)


def state_dicts_from_h5(path):
    """-> (config JSON string, {group: state_dict}), checked against the stored config."""
    import json
    import torch
    from weights_tools.reference.config import config_from_dict
    from weights_tools.h5weights import (WeightsError, describe_mismatch, expected_shapes,
                                         read_weights)
    cfg_dict, groups = read_weights(path)
    try:
        cfg = config_from_dict(cfg_dict, f"{path}: config")
    except ValueError as e:
        raise WeightsError(str(e)) from None
    expected = expected_shapes(cfg)
    out = {}
    for g, tensors in groups.items():
        problem = describe_mismatch(f"{path} ({g})", expected[g],
                                    {k: v.shape for k, v in tensors.items()})
        if problem:
            raise WeightsError(problem)
        sd = {}
        for k in sorted(tensors):
            v = tensors[k]
            if k.endswith(".num_batches_tracked"):
                sd[k] = torch.tensor(int(v), dtype=torch.int64)
            else:
                sd[k] = torch.from_numpy(v.copy())
        out[g] = sd
    return json.dumps(cfg_dict, sort_keys=True, separators=(",", ":")), out


def main(argv=None):
    a = parse_args(argv)
    torch = require_torch()
    from weights_tools.h5weights import WeightsError
    from weights_tools.checkpoints import COMBINED_FORMAT
    try:
        cfg_json, sds = state_dicts_from_h5(a.weights)
    except WeightsError as e:
        sys.stderr.write(f"import_h5: error: {e}\n")
        return 2
    obj = sds[a.group] if a.group else {"format": COMBINED_FORMAT, "version": 1,
                                        "config": cfg_json, **sds}
    from weights_tools.atomic import atomic_path
    with atomic_path(a.output) as tmp:
        torch.save(obj, tmp)
    print(f"wrote {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
