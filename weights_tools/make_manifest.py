#!/usr/bin/python3
"""Writes configs/<name>.manifest.json: every tensor name and shape a config's weights file
must hold, so the C++ side can verify weights without building the networks."""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from weights_tools.atomic import write_text_atomically  # noqa: E402
from weights_tools.torch_or_exit import require_torch  # noqa: E402


def manifest_text(m):
    """JSON with one tensor per line: readable, and diffs show which tensor changed."""
    head = {k: v for k, v in m.items() if k != "groups"}
    lines = ["{"] + [f" {json.dumps(k)}: {json.dumps(v, sort_keys=True)}," for k, v in head.items()]
    lines.append(' "groups": {')
    for gi, (g, tensors) in enumerate(m["groups"].items()):
        lines.append(f"  {json.dumps(g)}: [")
        for ti, t in enumerate(tensors):
            comma = "," if ti + 1 < len(tensors) else ""
            lines.append(f'   {{"name": {json.dumps(t["name"])}, "shape": {json.dumps(t["shape"])}}}{comma}')
        lines.append("  ]" + ("," if gi + 1 < len(m["groups"]) else ""))
    lines += [" }", "}"]
    text = "\n".join(lines) + "\n"
    assert json.loads(text) == m
    return text


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("configs", nargs="*", help="config names or files (default: every "
                   "configs/*.json that is not a manifest)")
    p.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 when a stored manifest is out of date")
    a = p.parse_args(argv)
    require_torch()
    from weights_tools.reference.config import CONFIG_DIR, ConfigError, load_config
    from weights_tools.h5weights import manifest
    names = a.configs or sorted(f[:-5] for f in os.listdir(CONFIG_DIR)
                                if f.endswith(".json") and not f.endswith(".manifest.json"))
    stale = 0
    for name in names:
        try:
            cfg = load_config(name)
        except ConfigError as e:
            sys.stderr.write(f"make_manifest: error: {e}\n")
            return 2
        text = manifest_text(manifest(cfg))
        out = os.path.join(CONFIG_DIR, f"{cfg.name}.manifest.json")
        if a.check:
            old = None
            if os.path.exists(out):
                with open(out) as f:
                    old = f.read()
            if old != text:
                print(f"{out}: out of date")
                stale += 1
            continue
        write_text_atomically(out, text)
        print(f"wrote {out}")
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
