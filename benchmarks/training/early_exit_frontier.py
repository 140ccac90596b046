#!/usr/bin/env python3
"""What early exit buys and costs, run setting by run setting, from `yelan eval --run --json` files.

    early_exit_frontier.py [--svg OUT.svg] SERIES [SERIES ...]

SERIES is NAME=TAG:FILE.json,TAG:FILE.json,... (the same recordings each time, one run
setting per file: a beta, an age cap, stage 1 on every tick). Prints a Markdown table (the
share of ticks that ran stage 1, the mask IoU as deployed, MPJPE root-aligned and with the
true head depth) and, with --svg, charts the root-aligned MPJPE and the mask IoU against the
share of ticks that ran stage 1: the cost in time is nearly linear in that share.
NAME@MS=...: MS is the series' stage 1 in ms a run (measured on one core); when every series
gives one, the table adds and the chart's x axis is stage 1's ms a tick (the share times MS),
so that stage 1 nets of different cost compare on one axis.
"""
import json
import sys

COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"]


def load(spec):
    name, _, items = spec.partition("=")
    name, _, ms = name.partition("@")
    points = []
    for item in items.split(","):
        tag, _, path = item.partition(":")
        with open(path) as f:
            j = json.load(f)
        points.append({"tag": tag, "share": 100 * j["mask_run_fraction"], "iou": j.get("mask_iou"),
                       "root": j["deployed"]["mpjpe_root_mm"], "paper": j["paper"]["mpjpe_mm"],
                       "cost": float(ms) * j["mask_run_fraction"] if ms else None})
    return name, sorted(points, key=lambda p: p["share"])


def panel(o, x0, y0, w, h, series, key, label, lo, hi, smax, xkey):
    o.append(f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="none" stroke="#888"/>')
    X = lambda s: x0 + w * s / smax
    unit, xlabel = ("%", "ticks that ran stage 1") if xkey == "share" else (" ms", "stage 1's time a tick, one core")
    Y = lambda v: y0 + h * (1 - (v - lo) / (hi - lo))
    for k in range(5):
        v = lo + (hi - lo) * k / 4
        o.append(f'<text x="{x0 - 6}" y="{Y(v) + 4:.1f}" text-anchor="end">{v:.3g}</text>')
        s = smax * k / 4
        o.append(f'<text x="{X(s):.1f}" y="{y0 + h + 16}" text-anchor="middle">{s:.3g}{unit}</text>')
    o.append(f'<text x="{x0 + w / 2}" y="{y0 + h + 34}" text-anchor="middle">{xlabel}</text>')
    o.append(f'<text x="{x0}" y="{y0 - 8}">{label}</text>')
    for i, (name, pts) in enumerate(series):
        c = COLOURS[i % len(COLOURS)]
        pts = [p for p in pts if p[key] is not None]
        pts = sorted(pts, key=lambda p: p[xkey])
        o.append('<polyline fill="none" stroke="%s" points="%s"/>' % (c, " ".join(f"{X(p[xkey]):.1f},{Y(p[key]):.1f}" for p in pts)))
        for p in pts:
            o.append(f'<circle cx="{X(p[xkey]):.1f}" cy="{Y(p[key]):.1f}" r="3" fill="{c}"/>')
            o.append(f'<text x="{X(p[xkey]) + 5:.1f}" y="{Y(p[key]) - 5:.1f}" font-size="10" fill="{c}">{p["tag"]}</text>')


def chart(series, path):
    W, H = 900, 380
    pts = [p for _, s in series for p in s]
    xkey = "cost" if all(p["cost"] is not None for p in pts) else "share"
    step = 25 if xkey == "share" else 2
    smax = max(step, step * -(-max(p[xkey] for p in pts) // step))
    roots = [p["root"] for p in pts]
    ious = [p["iou"] for p in pts if p["iou"] is not None]
    o = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
         '<rect width="100%" height="100%" fill="white"/>']
    panel(o, 70, 40, 340, 260, series, "root", "MPJPE as deployed, root-aligned (mm; lower is better)",
          min(roots) - 2, max(roots) + 2, smax, xkey)
    if ious:
        panel(o, 520, 40, 340, 260, series, "iou", "mask IoU as deployed (higher is better)", min(ious) - 0.01, max(ious) + 0.01, smax, xkey)
    for i, (name, _) in enumerate(series):
        o.append(f'<text x="{70 + 200 * i}" y="{H - 12}" fill="{COLOURS[i % len(COLOURS)]}">&#9679; {name}</text>')
    o.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(o) + "\n")


def main(argv):
    svg = None
    if len(argv) > 1 and argv[0] == "--svg":
        svg, argv = argv[1], argv[2:]
    if not argv:
        sys.exit(__doc__)
    series = [load(s) for s in argv]
    costs = all(p["cost"] is not None for _, s in series for p in s)
    print("| series | setting | stage 1 ran |" + (" stage 1 ms a tick |" if costs else "") +
          " mask IoU as deployed | MPJPE root-aligned | MPJPE, true head depth |")
    print("|---|---|---|" + ("---|" if costs else "") + "---|---|---|")
    for name, pts in series:
        for p in pts:
            iou = "n/a" if p["iou"] is None else f"{p['iou']:.3f}"
            cost = f" {p['cost']:.2f} |" if costs else ""
            print(f"| {name} | {p['tag']} | {p['share']:.0f}% |{cost} {iou} | {p['root']:.1f} | {p['paper']:.1f} |")
    if svg:
        chart(series, svg)
        print(f"wrote {svg}")


if __name__ == "__main__":
    main(sys.argv[1:])
