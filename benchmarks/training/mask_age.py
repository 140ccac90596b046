#!/usr/bin/env python3
"""What early exit costs, by the age of the mask stage 2 read.

    mask_age.py [--root] [--svg OUT.svg] EXIT.csv EVERY.csv

EXIT.csv and EVERY.csv are `yelan eval --run --poses` files of the same recordings, one run
with early exit (its poses' mask_age: 0 where stage 1 ran, k where stage 2 read a future
mask predicted k x 20 ms before) and one with stage 1 on every tick (--beta 1). Poses are
paired on (recording, time) where both say "person"; each pose's error is its mean over the
valid joints, at the true head depth (the paper protocol) or with --root after aligning the
hip centres. Prints, per age of EXIT's mask, the poses, both means and their paired
difference with its standard error; --svg charts the difference against the age.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paired import mean_se, pose_errors  # noqa: E402


def by_age(exit_csv, every_csv, mode):
    """{age: [(exit error, every-tick error) per paired pose]}, errors in mm."""
    every = {(s, t): e / n for s, t, _, e, n in pose_errors(every_csv, mode)}
    out = {}
    for s, t, age, e, n in pose_errors(exit_csv, mode):
        if (s, t) in every:
            out.setdefault(age, []).append((e / n, every[(s, t)]))
    return out


def summary(pairs):
    n = len(pairs)
    mean, se = mean_se([a - b for a, b in pairs])
    return n, sum(a for a, _ in pairs) / n, sum(b for _, b in pairs) / n, mean, se


def chart(rows, path, what):
    W, H, L, R, T, B = 560, 320, 60, 20, 40, 45
    ages = [r[0] for r in rows]
    lo = min(0.0, min(r[4] - 2 * r[5] for r in rows if r[5] == r[5]))
    hi = max(1.0, max(r[4] + 2 * r[5] for r in rows if r[5] == r[5]))
    X = lambda a: L + (a - min(ages) + 0.5) / (max(ages) - min(ages) + 1) * (W - L - R)
    Y = lambda v: T + (hi - v) / (hi - lo) * (H - T - B)
    o = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
         f'<rect width="{W}" height="{H}" fill="white"/>',
         f'<text x="{W / 2}" y="20" text-anchor="middle" font-size="14">Early exit against stage 1 on every tick, by mask age ({what})</text>',
         f'<line x1="{L}" y1="{Y(0):.1f}" x2="{W - R}" y2="{Y(0):.1f}" stroke="#888"/>']
    step = 10 if hi - lo > 40 else 5
    v = math.ceil(lo / step) * step
    while v <= hi:
        o.append(f'<text x="{L - 6}" y="{Y(v) + 4:.1f}" text-anchor="end">{v:g}</text>')
        o.append(f'<line x1="{L}" y1="{Y(v):.1f}" x2="{W - R}" y2="{Y(v):.1f}" stroke="#eee"/>')
        v += step
    for age, n, _, _, d, se in rows:
        x = X(age)
        o.append(f'<rect x="{x - 9:.1f}" y="{min(Y(d), Y(0)):.1f}" width="18" height="{abs(Y(d) - Y(0)):.1f}" '
                 f'fill="{"#c0392b" if d > 0 else "#2471a3"}"><title>age {age}: {d:+.1f} mm, {n} poses</title></rect>')
        if se == se:
            o.append(f'<line x1="{x:.1f}" y1="{Y(d - se):.1f}" x2="{x:.1f}" y2="{Y(d + se):.1f}" stroke="black"/>')
        o.append(f'<text x="{x:.1f}" y="{H - B + 16}" text-anchor="middle">{age}</text>')
    o.append(f'<text x="{(L + W - R) / 2}" y="{H - 8}" text-anchor="middle">age of the mask stage 2 read (frames of 20 ms since stage 1 ran)</text>')
    o.append(f'<text x="14" y="{(T + H - B) / 2}" text-anchor="middle" transform="rotate(-90 14 {(T + H - B) / 2})">'
             'MPJPE difference, mm (+- standard error)</text>')
    o.append("</svg>")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(o) + "\n")
    os.replace(tmp, path)


def main(argv):
    mode, svg = "true-depth", None
    while argv and argv[0].startswith("--"):
        if argv[0] == "--root":
            mode, argv = "root", argv[1:]
        elif argv[0] == "--svg" and len(argv) > 1:
            svg, argv = argv[1], argv[2:]
        else:
            sys.exit(__doc__)
    if len(argv) != 2:
        sys.exit(__doc__)
    groups = by_age(argv[0], argv[1], mode)
    if not groups:
        sys.exit(f"{argv[0]} and {argv[1]} share no scored pose")
    rows = [(age, *summary(groups[age])) for age in sorted(groups)]
    what = "root-aligned" if mode == "root" else "true head depth"
    print(f"mask age  poses  early exit mm  every tick mm  difference ({what})")
    for age, n, a, b, d, se in rows:
        print(f"{age:8d} {n:6d} {a:14.1f} {b:14.1f}  {d:+7.1f} +- {se:.1f}")
    n, a, b, d, se = summary([p for g in groups.values() for p in g])
    print(f"{'all':>8} {n:6d} {a:14.1f} {b:14.1f}  {d:+7.1f} +- {se:.1f}")
    if svg:
        chart(rows, svg, what)
        print(f"wrote {svg}")


if __name__ == "__main__":
    main(sys.argv[1:])
