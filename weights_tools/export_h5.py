#!/usr/bin/python3
"""State dicts / Lightning checkpoints -> our HDF5 weights file (see README.md)."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Write our HDF5 weights file (groups mask/ and pose/, one float32 dataset "
        "per state_dict key, root attributes format, version, config) from PyTorch "
        "checkpoints. Every tensor is checked by name and shape against --config.",
        epilog="Sources: a .pt holding a bare state_dict, a saved nn.Module, a Lightning "
        "checkpoint ('state_dict' with a 'model.'-like prefix), or the combined .pt that "
        "import_h5.py writes. A reference pose checkpoint also holds its U-Net under "
        "'mask_net.'; it is used for mask/ unless --mask is given.")
    p.add_argument("checkpoint", nargs="?", help="one file holding both networks")
    p.add_argument("--pose", help="checkpoint of the pose network")
    p.add_argument("--mask", help="checkpoint of the mask U-Net")
    p.add_argument("--pose-prefix", help="key prefix of the pose net (default: detected)")
    p.add_argument("--mask-prefix", help="key prefix of the U-Net (default: detected)")
    p.add_argument("--config", required=True, help="config name (weights_tools/configs) or JSON file")
    p.add_argument("--allow-downcast", action="store_true", help="accept float64 tensors (rounded)")
    p.add_argument("-o", "--output", required=True, help="output .h5 (written atomically)")
    a = p.parse_args(argv)
    if not (a.checkpoint or a.pose or a.mask):
        p.error("give a checkpoint, or --pose and --mask")
    return a


def main(argv=None):
    a = parse_args(argv)
    require_torch()
    from weights_tools.reference.config import ConfigError, load_config
    from weights_tools.h5weights import (WeightsError, describe_mismatch, expected_shapes,
                                         to_float32, write_weights)
    from weights_tools.checkpoints import load_checkpoint, extract_group, _LenientUnpickler
    _LenientUnpickler.stubbed.clear()

    try:
        cfg = load_config(a.config)
        expected = expected_shapes(cfg)
        groups = {}
        sources = {}
        for path in [a.checkpoint, a.pose, a.mask]:
            if path and path not in sources:
                sources[path] = load_checkpoint(path)
        for g in ("pose", "mask"):
            paths = [getattr(a, g)] if getattr(a, g) else [p for p in (a.checkpoint, a.pose) if p]
            for path in paths:
                kind, obj = sources[path]
                if kind == "combined":
                    sd = obj.get(g)
                    if sd is not None:
                        problem = describe_mismatch(f"{path} ({g})", expected[g],
                                                    {k: tuple(v.shape) for k, v in sd.items()})
                        if problem:
                            raise WeightsError(problem)
                else:
                    sd = extract_group(obj, g, expected[g], path, getattr(a, f"{g}_prefix"))
                if sd is not None:
                    groups[g] = {k: to_float32(k, v, path, a.allow_downcast) for k, v in sd.items()}
                    print(f"{g}: {len(sd)} tensors from {path}")
                    break
            if g not in groups:
                raise WeightsError(f"no {g} weights in {', '.join(paths)}"
                                   + (f" (pass --{g} FILE)" if not getattr(a, g) else ""))
        if _LenientUnpickler.stubbed:
            print("note: classes not importable here were skipped while unpickling: "
                  + ", ".join(sorted(_LenientUnpickler.stubbed)))
        write_weights(a.output, cfg.to_json(), groups)
    except (ConfigError, WeightsError) as e:
        sys.stderr.write(f"export_h5: error: {e}\n")
        return 2
    print(f"wrote {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
