#!/usr/bin/python3
"""Stage 1's mask IoU scene by scene for two or more models on the same recordings (the
`yelan eval --json` files of each; recordings with nobody left out), with the mean over
the scenes whose camera moves (names with "sweep" or "pan") and over the rest: a pooled
IoU hides whether a model is better everywhere or only on a few hard scenes.

    /usr/bin/python3 benchmarks/training/scene_iou.py NAME=EVAL.json NAME=EVAL.json ...
"""
import argparse
import json
import statistics

ap = argparse.ArgumentParser()
ap.add_argument("runs", nargs="+", help="NAME=EVAL.json")
args = ap.parse_args()

names, scenes = [], []
for arg in args.runs:
    name, _, path = arg.partition("=")
    if not path:
        ap.error(f"'{arg}': expected NAME=EVAL.json")
    try:
        with open(path) as f:
            by_scene = json.load(f)["mask_iou_by_condition"]["scene"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise SystemExit(f"scene_iou.py: {path}: not a `yelan eval --json` file with per-scene mask IoU ({e!r})")
    names.append(name)
    scenes.append(by_scene)
common = sorted(set.intersection(*(set(s) for s in scenes)))
dancers = [k for k in common if "-empty-" not in k and not k.split("-")[1].startswith("room")]
if not dancers:
    raise SystemExit("no recording with a dancer in all the files")


def moving(k):
    return "sweep" in k or "pan" in k


width = max(len(n) for n in names)
print("  ".join(n.rjust(max(width, 6)) for n in names) + "  recording")
for k in sorted(dancers, key=lambda k: scenes[0][k]):
    print("  ".join(f"{s[k]:.3f}".rjust(max(width, 6)) for s in scenes) + "  " + k)
for label, keys in (("moving camera", [k for k in dancers if moving(k)]), ("still camera", [k for k in dancers if not moving(k)])):
    if keys:
        means = "  ".join(f"{statistics.mean(s[k] for k in keys):.3f}".rjust(max(width, 6)) for s in scenes)
        print(f"{means}  mean over the {len(keys)} recordings with a dancer and a {label}")
