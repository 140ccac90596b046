#!/usr/bin/env bash
# Old (7f069ff) and new simulator binaries alternately, 3 rounds, one thread, 1 s of each
# kind of scene, wall seconds of `yelan sim` (writing the recording included).
P="ben-05_04-front-high-static ben-05_04-front-low-dynamic-occluded-flicker front-medium-dynamic-flicker-empty front-medium-static-clutter-shake-empty front-medium-static-clutter-sweep-empty ben-05_04-front-high-dynamic-clutter-sweep"
NEW=${NEW:-/work/main/build/release/yelan}
echo "preset round binary wall_s events"
for r in 1 2 3; do
  for p in $P; do
    for b in /var/tmp/yelan-data/bin/yelan-7f069ff $NEW; do
      s=$(date +%s.%N)
      line=$($b sim --preset $p --duration 1s --threads 1 -o /tmp/bench-sim-ab.yelan.h5 2>&1 | tail -1)
      e=$(date +%s.%N)
      echo "$p $r $(basename $b) $(echo "$e - $s" | bc) $(echo "$line" | sed -n 's/.*: \([0-9]*\) events.*/\1/p')"
    done
  done
done
