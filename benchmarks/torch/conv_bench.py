#!/usr/bin/python3
"""Times PyTorch's CPU convolutions on the shapes `yelan bench kernels` sends on stdin.

Input: a JSON object {"threads": [1, 2], "reps": 5, "cases": [{"where", "cin", "cout", "h",
"w", "k", "stride", "pad", "transposed", "out_pad_h", "out_pad_w", "ops": [...]}]}.
Output: one JSON array of {"where", "op", "threads", "ms"} (median of reps). Backward passes
use aten.convolution_backward with one output requested, as autograd would call it.
Runs only under Debian's /usr/bin/python3 (python3-torch 1.13).
"""
import json
import sys
import time

import torch


def seconds_per_call(fn, reps, min_run_s):
    fn()
    runs = []
    for _ in range(reps):
        calls, t0 = 0, time.perf_counter()
        while True:
            fn()
            calls += 1
            t1 = time.perf_counter()
            if t1 - t0 >= min_run_s:
                break
        runs.append((t1 - t0) / calls)
    runs.sort()
    return runs[len(runs) // 2]


def bench_case(c, reps):
    k, s, p = c["k"], c["stride"], c["pad"]
    transposed = c.get("transposed", False)
    op_pad = [c.get("out_pad_h", 0), c.get("out_pad_w", 0)] if transposed else [0, 0]
    x = torch.randn(1, c["cin"], c["h"], c["w"])
    w = torch.randn(c["cin"], c["cout"], k, k) if transposed else torch.randn(c["cout"], c["cin"], k, k)
    with torch.no_grad():
        if transposed:
            fwd = lambda: torch.nn.functional.conv_transpose2d(x, w, stride=s, padding=p, output_padding=op_pad)
        else:
            fwd = lambda: torch.nn.functional.conv2d(x, w, stride=s, padding=p)
        gy = torch.randn_like(fwd())

        def backward(mask):
            return lambda: torch.ops.aten.convolution_backward(
                gy, x, w, None, [s, s], [p, p], [1, 1], transposed, op_pad, 1, mask)

        kind = "deconv2d" if transposed else "conv2d"
        fns = {kind + ".fwd": fwd, kind + ".bwd_data": backward([True, False, False]),
               kind + ".bwd_weights": backward([False, True, False])}
        out = {}
        for op in c["ops"]:
            if op in fns:
                out[op] = seconds_per_call(fns[op], reps, 0.05) * 1e3
        return out


def main():
    req = json.load(sys.stdin)
    results = []
    for t in req["threads"]:
        torch.set_num_threads(t)
        for c in req["cases"]:
            for op, ms in bench_case(c, req.get("reps", 5)).items():
                results.append({"where": c["where"], "op": op, "threads": t, "ms": ms})
    json.dump(results, sys.stdout)
    print()


if __name__ == "__main__":
    main()
