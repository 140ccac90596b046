#!/usr/bin/env python3
"""Markdown tables from `yelan bench kernels --json` output (plain Python 3, no deps).

usage: benchmarks/kernels_table.py RESULTS.json [RESULTS2.json ...] > table.md
Compute-bound rows: GFLOP/s, % of the FMA peak measured in the same run, and ratios to
oneDNN and PyTorch. Memory-bound rows: time as a multiple of a memcpy of the same bytes.
With several files (repeated runs), each figure is the median over the files.
"""
import json
import statistics
import sys


def key(r):
    return (r["where"], r["op"], r["algo"], r["isa"], r["threads"])


def main(paths):
    runs = [json.load(open(p)) for p in paths]
    groups = {}
    order = []
    for run in runs:
        for r in run:
            k = key(r)
            if k not in groups:
                groups[k] = []
                order.append(k)
            groups[k].append(r)

    def med(rows, field):
        vals = [r[field] for r in rows if r.get(field, 0) > 0]
        return statistics.median(vals) if vals else None

    print("| where | op | kernel | cin->cout | input | isa | thr | ms | GFLOP/s | % peak | oneDNN GFLOP/s | ours/oneDNN | torch GFLOP/s | ours/torch |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k in order:
        rows = groups[k]
        r = rows[0]
        if r.get("bytes", 0) > 0:
            continue
        g, pk = med(rows, "gflops"), med(rows, "pct_peak")
        one, tor = med(rows, "onednn_gflops"), med(rows, "torch_gflops")
        op = r["op"] + ("" if r["algo"] == "direct" else " (" + r["algo"] + ")")
        cells = [r["where"], op, "%dx%d/%d" % (r["kh"], r["kw"], r["stride"]), "%d->%d" % (r["cin"], r["cout"]),
                 "%dx%d" % (r["h"], r["w"]), r["isa"], str(r["threads"]), "%.3f" % med(rows, "ms"),
                 "%.1f" % g, "%.1f" % pk if pk else "-",
                 "%.1f" % one if one else "-", "%.2f" % (g / one) if one else "-",
                 "%.1f" % tor if tor else "-", "%.2f" % (g / tor) if tor else "-"]
        print("| " + " | ".join(cells) + " |")
    mem = [k for k in order if groups[k][0].get("bytes", 0) > 0]
    if mem:
        print()
        print("| where | op | channels x HxW | isa | thr | ms | GB/s | x memcpy of the same bytes |")
        print("|---|---|---|---|---|---|---|---|")
        for k in mem:
            rows = groups[k]
            r = rows[0]
            ms = med(rows, "ms")
            ratio = statistics.median([x["ms"] / x["memcpy_ms"] for x in rows])
            print("| %s | %s | %dx%dx%d | %s | %d | %.3f | %.1f | %.2f |" % (
                r["where"], r["op"], r["cin"], r["h"], r["w"], r["isa"], r["threads"], ms, r["bytes"] / ms / 1e6, ratio))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
