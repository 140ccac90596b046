#!/usr/bin/env python3
"""The comparison table (a)-(f) and the accuracy/speed frontier of issue 7, from the files
benchmarks/training/run.sh leaves in RESULTS (default benchmarks/results/training):
  eval-<id>.json   yelan eval --json on the test split
  log-<id>.csv     the trainer's log (steps, wall time)
  speed-<id>.json  yelan bench run --weights <model> --threads-list 1 --json, one per early-exit
                   setting: speed-<id>.json (beta 1: stage 1 every tick) and speed-<id>-exit.json
Writes RESULTS/table.md, RESULTS/summary.json and CHARTS/frontier-1t.svg (+ .png with
rsvg-convert when installed). Standard library only.
  benchmarks/training/report.py [--results DIR] [--charts DIR]"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)
from weights_tools.atomic import atomic_path, write_text_atomically  # noqa: E402  (standard library only)


def load_json(path):
    with open(path) as f:
        return json.load(f)


def training_of(path):
    """steps, wall minutes, best validation loss and its step, from a trainer log."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None
    vals = [(float(r["val_loss"]), int(r["step"])) for r in rows if float(r["val_loss"]) >= 0]
    best = min(vals) if vals else (float("nan"), 0)
    return {"steps": int(rows[-1]["step"]), "minutes": float(rows[-1]["wall_s"]) / 60,
            "best_val": best[0], "best_step": best[1]}


def speed_of(path):
    if not os.path.exists(path):
        return None
    rows = [r for r in load_json(path) if r["threads"] == 1]
    return {"ms_per_pose": 1000.0 / rows[0]["poses_per_s"], "mask_run_fraction": rows[0]["mask_run_fraction"]} if rows else None


def collect(results, spec, group):
    out = []
    for m in spec[group]:
        i = m["id"]
        ev_path = os.path.join(results, f"eval-{i}.json")
        log_path = os.path.join(results, f"log-{i}.csv")
        if not os.path.exists(ev_path):
            if os.path.exists(log_path):  # a run still going or stopped: its progress, no scores
                row = dict(m, training=training_of(log_path), speed=None, speed_exit=None, mpjpe_mm=None, pck150=None,
                           auc=None, mpjpe_root_mm=None, mpjpe_clear_mm=None, mpjpe_occluded_mm=None, mask_iou=None)
                row["name"] += " (not finished: no evaluation yet)"
                out.append(row)
            else:
                print(f"report: no {ev_path} yet; {i} left out", file=sys.stderr)
            continue
        ev = load_json(ev_path)
        occ = ev.get("by_condition", {}).get("occlusion", {})
        row = dict(m)
        row.update({
            "mpjpe_mm": ev["mpjpe_mm"], "pck150": ev["pck150"], "auc": ev["auc"], "mpjpe_root_mm": ev["mpjpe_root_mm"],
            "mpjpe_clear_mm": occ.get("clear", {}).get("mpjpe_mm"), "mpjpe_occluded_mm": occ.get("occluded", {}).get("mpjpe_mm"),
            "mask_iou": ev.get("mask_iou"), "frames": ev["frames"], "scenes": ev.get("scenes"),
            "training": training_of(log_path) if os.path.exists(log_path) else None,
            "speed": speed_of(os.path.join(results, f"speed-{i}.json")),
            "speed_exit": speed_of(os.path.join(results, f"speed-{i}-exit.json")),
        })
        out.append(row)
    return out


def fmt(v, digits=1):
    return "-" if v is None else f"{v:.{digits}f}"


def table(rows, sizes=False):
    head = ("| | method | MPJPE mm | PCK@150 | AUC | root-aligned MPJPE | MPJPE clear / occluded | mask IoU | training |"
            + (" ms/pose (stage 1 every tick / early exit) |" if sizes else ""))
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        t = r["training"]
        # wall minutes are not shown: runs shared the cores and resumed runs restart the clock
        train = f"{t['steps']} steps (best validation {t['best_val']:.3f} at step {t['best_step']})" if t else "-"
        iou = fmt(r["mask_iou"], 3) if r["mask_iou"] else "-"
        line = (f"| {r['id']} | {r['name']} | {fmt(r['mpjpe_mm'])} | {fmt(r['pck150'], 3)} | {fmt(r['auc'], 3)} | "
                f"{fmt(r['mpjpe_root_mm'])} | {fmt(r['mpjpe_clear_mm'])} / {fmt(r['mpjpe_occluded_mm'])} | {iou} | {train} |")
        if sizes:
            s, e = r["speed"], r["speed_exit"]
            line += f" {fmt(s and s['ms_per_pose'])} / {fmt(e and e['ms_per_pose'])} |"
        lines.append(line)
    return "\n".join(lines) + "\n"


def nice_ticks(lo, hi, n=5):
    span = hi - lo
    step = 10 ** int(f"{span / n:e}".split("e")[1])
    for m in (1, 2, 5, 10):
        if span / (step * m) <= n:
            step *= m
            break
    first = step * int(lo / step)
    ticks = []
    v = first
    while v <= hi + 1e-9:
        if v >= lo - 1e-9:
            ticks.append(v)
        v += step
    return ticks


def frontier_svg(rows, path):
    series = [("speed", "stage 1 every tick", "#c0392b"), ("speed_exit", "early exit (beta 0.9)", "#2471a3")]
    pts = [(r[k]["ms_per_pose"], r["mpjpe_mm"], r["name"], c) for r in rows for k, _, c in series if r.get(k)]
    if not pts:
        print("report: no speed figures; no chart", file=sys.stderr)
        return False
    W, H, L, R, T, B = 720, 440, 70, 30, 50, 60
    xs, ys = [p[0] for p in pts], [p[1] for p in pts]
    x0, x1 = 0, max(xs) * 1.15
    y0, y1 = min(ys) * 0.9, max(ys) * 1.08
    X = lambda v: L + (v - x0) / (x1 - x0) * (W - L - R)
    Y = lambda v: H - B - (v - y0) / (y1 - y0) * (H - T - B)
    o = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
         f'<rect width="{W}" height="{H}" fill="white"/>',
         f'<text x="{W / 2}" y="24" text-anchor="middle" font-size="15">MPJPE against milliseconds per pose, 1 core '
         f'(test split, {rows[0].get("scenes", "?")} scenes)</text>']
    for t in nice_ticks(x0, x1):
        o.append(f'<line x1="{X(t):.1f}" y1="{T}" x2="{X(t):.1f}" y2="{H - B}" stroke="#eee"/>'
                 f'<text x="{X(t):.1f}" y="{H - B + 16}" text-anchor="middle">{t:g}</text>')
    for t in nice_ticks(y0, y1):
        o.append(f'<line x1="{L}" y1="{Y(t):.1f}" x2="{W - R}" y2="{Y(t):.1f}" stroke="#eee"/>'
                 f'<text x="{L - 6}" y="{Y(t) + 4:.1f}" text-anchor="end">{t:g}</text>')
    o.append(f'<line x1="{L}" y1="{H - B}" x2="{W - R}" y2="{H - B}" stroke="black"/>'
             f'<line x1="{L}" y1="{T}" x2="{L}" y2="{H - B}" stroke="black"/>'
             f'<text x="{(L + W - R) / 2}" y="{H - 18}" text-anchor="middle">ms per pose (yelan bench run, 1 thread)</text>'
             f'<text transform="translate(18,{(T + H - B) / 2}) rotate(-90)" text-anchor="middle">MPJPE (mm, lower is better)</text>')
    for key, label, colour in series:
        line = sorted((r[key]["ms_per_pose"], r["mpjpe_mm"]) for r in rows if r.get(key))
        if len(line) > 1:
            o.append('<polyline fill="none" stroke="%s" stroke-dasharray="4 3" points="%s"/>'
                     % (colour, " ".join(f"{X(a):.1f},{Y(b):.1f}" for a, b in line)))
    for x, y, name, colour in pts:
        o.append(f'<circle cx="{X(x):.1f}" cy="{Y(y):.1f}" r="5" fill="{colour}"/>'
                 f'<text x="{X(x) + 8:.1f}" y="{Y(y) - 6:.1f}">{name}</text>')
    for i, (_, label, colour) in enumerate(series):
        o.append(f'<circle cx="{W - R - 170}" cy="{T + 12 + 18 * i}" r="5" fill="{colour}"/>'
                 f'<text x="{W - R - 160}" y="{T + 16 + 18 * i}">{label}</text>')
    o.append("</svg>\n")
    write_text_atomically(path, "\n".join(o))
    if shutil.which("rsvg-convert"):
        with atomic_path(path[:-4] + ".png") as tmp:
            subprocess.run(["rsvg-convert", "-o", os.path.abspath(tmp), os.path.abspath(path)], check=True)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--results", default=os.path.join(ROOT, "benchmarks/results/training"))
    ap.add_argument("--charts", default=os.path.join(ROOT, "benchmarks/charts"))
    a = ap.parse_args()
    spec = load_json(os.path.join(HERE, "methods.json"))
    cmp_rows, size_rows = collect(a.results, spec, "comparison"), collect(a.results, spec, "sizes")
    text = "### Comparison (a)-(f)\n\n" + table(cmp_rows) + "\n### Model sizes\n\n" + table(size_rows, sizes=True)
    write_text_atomically(os.path.join(a.results, "table.md"), text)
    write_text_atomically(os.path.join(a.results, "summary.json"),
                          json.dumps({"comparison": cmp_rows, "sizes": size_rows}, indent=1))
    print(text)
    scored = [r for r in size_rows if r["mpjpe_mm"] is not None]
    if scored:
        best = min(r["mpjpe_mm"] for r in scored)
        ok = [r for r in scored if r["mpjpe_mm"] <= 1.1 * best and r.get("speed")]
        if ok:
            pick = min(ok, key=lambda r: r["speed"]["ms_per_pose"])
            print(f"default: {pick['id']} ({pick['name']}): {pick['mpjpe_mm']:.1f} mm, best {best:.1f} mm, "
                  f"{pick['speed']['ms_per_pose']:.1f} ms/pose")
        os.makedirs(a.charts, exist_ok=True)
        frontier_svg(scored, os.path.join(a.charts, "frontier-1t.svg"))


if __name__ == "__main__":
    main()
