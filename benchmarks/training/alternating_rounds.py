#!/usr/bin/env python3
"""alternating_rounds.py RAW: the summary of alternating bench rounds, RAW holding lines
"old|new ROUND POSES_PER_S"; each series, the ratio per round, and the medians."""
import statistics as st
import sys

old, new = [], []
for line in open(sys.argv[1]):
    w, _, v = line.split()
    (old if w == 'old' else new).append(float(v))
print('old', ' '.join(f'{x:.1f}' for x in old))
print('new', ' '.join(f'{x:.1f}' for x in new))
print('new/old per round', ' '.join(f'{b / a:.3f}' for a, b in zip(old, new)))
print(f'median old {st.median(old):.1f}, new {st.median(new):.1f} (x{st.median(new) / st.median(old):.3f})')
