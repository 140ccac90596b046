#!/usr/bin/env python3
"""Learning curves of yelan training runs: validation MPJPE (mm, paper protocol, on the held-out
validation windows) against the training frames seen and against CPU-hours, one line per run,
with the floors of an eval JSON (trivial predictors on the test frames) as dashed lines.
Reads RUN/log.csv and RUN/run.json as `yelan train` writes them. Standard library only.
  benchmarks/training/curves.py RUN [RUN ...] --out CHART.svg [--floors EVAL.json] [--csv OUT.csv]
                               [--mark STEP:TEXT ...]
Also prints, per run, the best validation MPJPE, where it was reached and what it cost."""
import argparse
import csv
import html
import json
import math
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from weights_tools.atomic import atomic_path, write_text_atomically  # noqa: E402  (standard library only)

COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]


def load_run(path):
    with open(os.path.join(path, "run.json")) as f:
        meta = json.load(f)
    frames_per_step = meta["batch"] * meta["window"]
    points = []
    with open(os.path.join(path, "log.csv")) as f:
        for r in csv.DictReader(f):
            mm = float(r.get("val_mpjpe_mm") or -1)
            if mm < 0:
                continue
            points.append({"step": int(r["step"]), "frames": int(r["step"]) * frames_per_step,
                           "cpu_h": float(r.get("cpu_s") or 0) / 3600, "mpjpe": mm})
    return {"name": os.path.basename(os.path.normpath(path)), "meta": meta, "points": points}


def svg_panel(x0, y0, w, h, runs, key, xlabel, ymax, floors, logx, marks=()):
    out = []
    xs = [p[key] for r in runs for p in r["points"] if p[key] > 0]
    if not xs:
        return out
    lo, hi = (min(xs), max(xs)) if logx else (0, max(xs))
    if hi <= lo:
        hi = lo * 2 if lo > 0 else 1

    def px(v):
        if logx:
            return x0 + w * (math.log10(max(v, lo)) - math.log10(lo)) / (math.log10(hi) - math.log10(lo))
        return x0 + w * (v - lo) / (hi - lo)

    def py(v):
        return y0 + h - h * min(v, ymax) / ymax

    out.append(f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="none" stroke="#888"/>')
    for k in range(6):
        v = ymax * k / 5
        out.append(f'<line x1="{x0}" x2="{x0 + w}" y1="{py(v):.1f}" y2="{py(v):.1f}" stroke="#eee"/>')
        out.append(f'<text x="{x0 - 6}" y="{py(v) + 4:.1f}" text-anchor="end" font-size="11">{v:.0f}</text>')
    for k in range(5):
        v = lo + (hi - lo) * k / 4 if not logx else 10 ** (math.log10(lo) + (math.log10(hi) - math.log10(lo)) * k / 4)
        label = f"{v:.3g}" if key == "cpu_h" else (f"{v / 1e3:.0f}k" if v >= 1e3 else f"{v:.0f}")
        out.append(f'<text x="{px(v):.1f}" y="{y0 + h + 16}" text-anchor="middle" font-size="11">{label}</text>')
    out.append(f'<text x="{x0 + w / 2}" y="{y0 + h + 34}" text-anchor="middle" font-size="12">{xlabel}</text>')
    for i, (name, mm) in enumerate(sorted(floors.items())):
        out.append(f'<line x1="{x0}" x2="{x0 + w}" y1="{py(mm):.1f}" y2="{py(mm):.1f}" stroke="#777" '
                   f'stroke-dasharray="5,4"/>')
        out.append(f'<text x="{x0 + w - 4}" y="{py(mm) - 3:.1f}" text-anchor="end" font-size="10" fill="#555">'
                   f'{name} {mm:.0f} mm</text>')
    for step, text in marks:  # at the first run's first validation at or after STEP
        at = next((p for p in runs[0]["points"] if p["step"] >= step and p[key] > 0), None)
        if at is None:
            continue
        out.append(f'<line x1="{px(at[key]):.1f}" x2="{px(at[key]):.1f}" y1="{y0}" y2="{y0 + h}" stroke="#999" '
                   f'stroke-dasharray="2,3"/>')
        out.append(f'<text x="{px(at[key]) - 4:.1f}" y="{y0 + 14}" text-anchor="end" font-size="10" fill="#555">'
                   f'{html.escape(text)}</text>')
    for i, r in enumerate(runs):
        pts = [p for p in r["points"] if p[key] > 0]
        if not pts:
            continue
        c = COLOURS[i % len(COLOURS)]
        d = " ".join(f"{px(p[key]):.1f},{py(p['mpjpe']):.1f}" for p in pts)
        out.append(f'<polyline points="{d}" fill="none" stroke="{c}" stroke-width="2"/>')
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--floors", help="an eval JSON whose floors are drawn as dashed lines")
    ap.add_argument("--csv", help="also write the points as CSV")
    ap.add_argument("--title", default="Validation MPJPE (paper protocol) while training")
    ap.add_argument("--mark", action="append", default=[], metavar="STEP:TEXT",
                    help="a dotted vertical line at the first run's step STEP (e.g. where its validation sample changed)")
    a = ap.parse_args()
    marks = []
    for m in a.mark:
        step, sep, text = m.partition(":")
        if not sep or not step.isdigit():
            ap.error(f"--mark {m!r}: expected STEP:TEXT, STEP a whole number")
        marks.append((int(step), text))
    runs = [load_run(r) for r in a.runs]
    floors = {}
    if a.floors:
        with open(a.floors) as f:
            ev = json.load(f)
        floors = {k: v["mpjpe_mm"] for k, v in ev.get("floors", {}).items()}
    ys = [p["mpjpe"] for r in runs for p in r["points"]] + list(floors.values())
    ymax = max(100.0, min(max(ys) if ys else 500, 800) * 1.05)
    ymax = math.ceil(ymax / 50) * 50
    W, H = 980, 430 + 18 * ((len(runs) - 1) // 2)  # two legend entries a row
    body = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif">',
            f'<rect width="{W}" height="{H}" fill="white"/>',
            f'<text x="{W / 2}" y="22" text-anchor="middle" font-size="15">{a.title}</text>',
            f'<text x="16" y="{H / 2}" transform="rotate(-90 16 {H / 2})" text-anchor="middle" font-size="12">'
            f'MPJPE (mm)</text>']
    body += svg_panel(70, 50, 390, 300, runs, "frames", "training frames seen", ymax, floors, False, marks)
    body += svg_panel(560, 50, 390, 300, runs, "cpu_h", "CPU-hours", ymax, floors, False, marks)
    for i, r in enumerate(runs):
        c = COLOURS[i % len(COLOURS)]
        y = 405 + 18 * (i // 2)
        x = 70 + (i % 2) * 450
        body.append(f'<line x1="{x}" x2="{x + 24}" y1="{y - 4}" y2="{y - 4}" stroke="{c}" stroke-width="3"/>')
        body.append(f'<text x="{x + 30}" y="{y}" font-size="12">{r["name"]} ({r["meta"]["config"]})</text>')
    body.append("</svg>")
    write_text_atomically(a.out, "\n".join(body) + "\n")
    if shutil.which("rsvg-convert") and a.out.endswith(".svg"):
        try:  # the PNG is a convenience; the SVG is the result
            with atomic_path(a.out[:-4] + ".png") as tmp:
                subprocess.run(["rsvg-convert", "-o", os.path.abspath(tmp), os.path.abspath(a.out)], check=True)
        except subprocess.CalledProcessError:
            pass
    if a.csv:
        with atomic_path(a.csv) as tmp, open(tmp, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["run", "config", "step", "frames", "cpu_h", "val_mpjpe_mm"])
            for r in runs:
                for p in r["points"]:
                    w.writerow([r["name"], r["meta"]["config"], p["step"], p["frames"], f"{p['cpu_h']:.4f}",
                                f"{p['mpjpe']:.1f}"])
    for r in runs:
        if not r["points"]:
            print(f"{r['name']}: no validation yet")
            continue
        best = min(r["points"], key=lambda p: p["mpjpe"])
        last = r["points"][-1]
        print(f"{r['name']} ({r['meta']['config']}): best validation MPJPE {best['mpjpe']:.1f} mm at step "
              f"{best['step']} ({best['frames']} frames, {best['cpu_h']:.2f} CPU-h); last {last['mpjpe']:.1f} mm at "
              f"step {last['step']} ({last['cpu_h']:.2f} CPU-h)")


if __name__ == "__main__":
    main()
