#!/usr/bin/env python3
"""One markdown row per `yelan eval --json` file: what the stick and event runs are compared
by (MPJPE, the better of each pose and its left/right mirror, the image error and the hands',
the depth error, after aligning the hips' depths in brackets where the file has it, the back
and front views' swap shares), beside the per-view floor on the same frames.

    eval_rows.py NAME=FILE.json [NAME=FILE.json ...]
"""
import json
import sys


def depth(split):
    root = split.get("mean_depth_root_mm")
    return f"{split['mean_depth_mm']:.1f}" + (f" ({root:.1f})" if root is not None else "")


def row(name, path):
    d = json.load(open(path))
    img = d["error_split"]["model"]
    swap = d.get("swap_share_by_view", {})
    floor = d["floors"]["per_view_mean_pose_at_hip"]["mpjpe_mm"]
    fimg = d["error_split"]["per_view_mean_pose_at_hip"]
    share = " / ".join(f"{100 * swap[v]:.0f}%" if v in swap else "n/a" for v in ("back", "front"))
    return (f"| {name} | {d['mpjpe_mm']:.1f} | {d['swap_oracle']['mpjpe_mm']:.1f} | "
            f"{img['mean_image_px']:.1f} ({img['image_px']['handR']:.1f} / {img['image_px']['handL']:.1f}) | "
            f"{depth(img)} | {share} | "
            f"{floor:.1f}, {fimg['mean_image_px']:.1f} px, {depth(fimg)} | {d['frames']} |")


def main(args):
    if not args or any("=" not in a for a in args):
        sys.exit(__doc__)
    print("| run | MPJPE mm | better of pose and mirror mm | image px (hands R / L) | depth mm (hip-aligned) | swap share back / front | per-view floor: mm, px, depth mm (hip-aligned) | frames |")
    print("|---|---|---|---|---|---|---|---|")
    for a in args:
        name, path = a.split("=", 1)
        print(row(name, path))


if __name__ == "__main__":
    main(sys.argv[1:])
