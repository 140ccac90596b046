"""benchmarks/training/paired.py: two pose nets compared recording by recording, on eval
JSON files whose differences are known by hand. Standard library only.

Run: /usr/bin/python3 -m unittest discover -s weights_tools/tests"""
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PAIRED = os.path.join(ROOT, "benchmarks", "training", "paired.py")
MASK_AGE = os.path.join(ROOT, "benchmarks", "training", "mask_age.py")


def write_eval(path, scenes):
    with open(path, "w") as f:
        json.dump({"by_condition": {"scene": {k: {"mpjpe_mm": v, "frames": 96} for k, v in scenes.items()}}}, f)


def write_poses(path, rows, ages=None):
    """rows: (source, person, pred 13x3 or None, truth 13x3, head_depth) as yelan eval --run --poses
    writes them; ages: each row's mask_age (0 for all when None)."""
    head = ["source", "t_us", "dancer", "person", "confidence", "mask_ran", "head_depth_mm", "true_head_depth_mm"]
    head += [f"{w}j{j}_{c}" for w in ("", "true_") for j in range(13) for c in "xyz"] + [f"valid{j}" for j in range(13)]
    with open(path, "w") as f:
        f.write(",".join(head + ["mask_age"]) + "\n")
        for t, (source, person, pred, truth, depth) in enumerate(rows):
            age = ages[t] if ages else 0
            cells = [source, str(t * 20000), "1", str(person), "0.9", str(int(age == 0)), str(depth), str(truth[0][2])]
            cells += [str(v) if person else "" for p in (pred or [[0, 0, 0]] * 13) for v in p]
            cells += [str(v) for p in truth for v in p] + ["1"] * 13 + [str(age)]
            f.write(",".join(cells) + "\n")


TRUTH = [[10.0 * j, 5.0 * j, 3000.0 + j] for j in range(13)]


def moved(pose, d):
    return [[p[c] + d[c] for c in range(3)] for p in pose]


class PairedTest(unittest.TestCase):
    def run_paired(self, *files):
        return subprocess.run([sys.executable, PAIRED, *files], capture_output=True, text=True)

    def test_differences_pooled_over_pairs(self):
        with tempfile.TemporaryDirectory() as d:
            f = {n: os.path.join(d, n + ".json") for n in ("a1", "b1", "a2", "b2")}
            # B - A: -10 and +0 in the first pair, -20 in the second: mean -10, sd 10, SE 10/sqrt(3).
            write_eval(f["a1"], {"x": 100, "y": 200})
            write_eval(f["b1"], {"x": 90, "y": 200})
            write_eval(f["a2"], {"z": 150})
            write_eval(f["b2"], {"z": 130})
            r = self.run_paired(f["a1"], f["b1"], f["a2"], f["b2"])
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("3 recordings: B - A = -10.0 +- 5.8 mm", r.stdout)
            self.assertIn("B better on 2", r.stdout)

    def test_refuses_files_of_different_recordings(self):
        with tempfile.TemporaryDirectory() as d:
            a, b = os.path.join(d, "a.json"), os.path.join(d, "b.json")
            write_eval(a, {"x": 100, "y": 200})
            write_eval(b, {"x": 90, "w": 200})
            r = self.run_paired(a, b)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("score different recordings", r.stderr)

    def test_deployed_poses_as_placed_root_aligned_and_at_the_true_depth(self):
        with tempfile.TemporaryDirectory() as d:
            a, b = os.path.join(d, "a.csv"), os.path.join(d, "b.csv")
            z = TRUTH[0][2]
            # A: every joint 10 mm off in x, its head depth right; B: 5 mm off (0, 4, 3), and
            # on the second recording twice as far in every coordinate with its head depth
            # doubled (exact at the true depth). A pose saying nobody is left out.
            write_poses(a, [("r1", 1, moved(TRUTH, (10, 0, 0)), TRUTH, z), ("r1", 0, None, TRUTH, -1),
                            ("r2", 1, moved(TRUTH, (10, 0, 0)), TRUTH, z)])
            write_poses(b, [("r1", 1, moved(TRUTH, (0, 4, 3)), TRUTH, z), ("r1", 0, None, TRUTH, -1),
                            ("r2", 1, [[2 * v for v in p] for p in TRUTH], TRUTH, 2 * z)])
            r = self.run_paired("--poses", "--true-depth", a, b)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("2 recordings: B - A = -7.5 +- 2.5 mm", r.stdout)
            self.assertIn("B better on 2", r.stdout)
            # Root-aligned, a constant offset is no error: r1 0 - 0; r2 B doubled about the hips
            # is off by each joint's distance from them.
            root = [(TRUTH[5][c] + TRUTH[6][c]) / 2 for c in range(3)]
            r2 = sum(math.dist(p, root) for p in TRUTH) / 13
            r = self.run_paired("--poses", "--root", a, b)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn(f"2 recordings: B - A = {r2 / 2:+.1f} +- {r2 / 2:.1f} mm", r.stdout)
            self.assertIn("B better on 0", r.stdout)
            r = self.run_paired("--poses", a, b)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("B better on 1", r.stdout)  # r1 -5; r2 a dancer twice as far is far worse

    def test_common_scores_only_the_poses_both_files_score(self):
        with tempfile.TemporaryDirectory() as d:
            a, b = os.path.join(d, "a.csv"), os.path.join(d, "b.csv")
            z = TRUTH[0][2]
            # A says nobody on r1's second pose and on all of r2; B scores them, badly (30 mm).
            # On their common pose B is 5 mm better (5 against 10).
            write_poses(a, [("r1", 1, moved(TRUTH, (10, 0, 0)), TRUTH, z), ("r1", 0, None, TRUTH, -1),
                            ("r2", 0, None, TRUTH, -1)])
            write_poses(b, [("r1", 1, moved(TRUTH, (5, 0, 0)), TRUTH, z), ("r1", 1, moved(TRUTH, (30, 0, 0)), TRUTH, z),
                            ("r2", 1, moved(TRUTH, (30, 0, 0)), TRUTH, z)])
            r = self.run_paired("--poses", a, b)
            self.assertNotEqual(r.returncode, 0)  # r2 scored by B alone
            self.assertIn("score different recordings", r.stderr)
            r = self.run_paired("--poses", "--common", a, b)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("1 recordings: B - A = -5.0 +- nan mm", r.stdout)
            self.assertIn("B better on 1", r.stdout)

    def test_mask_age_pairs_poses_by_time_and_groups_them_by_the_age_of_the_mask(self):
        with tempfile.TemporaryDirectory() as d:
            exit_, every, svg = os.path.join(d, "x.csv"), os.path.join(d, "e.csv"), os.path.join(d, "age.svg")
            z = TRUTH[0][2]
            # Early exit: ages 0, 1, 2, 0, 1 on one recording, each joint off in x by 2 mm a frame
            # of age (0, 2, 4, 0, 2); stage 1 on every tick: every pose 1 mm off. The last pose says
            # nobody on the every-tick run: not paired.
            ages = [0, 1, 2, 0, 1]
            write_poses(exit_, [("r", 1, moved(TRUTH, (2 * a, 0, 0)), TRUTH, z) for a in ages], ages)
            write_poses(every, [("r", 1, moved(TRUTH, (1, 0, 0)), TRUTH, z)] * 4 + [("r", 0, None, TRUTH, -1)])
            r = subprocess.run([sys.executable, MASK_AGE, "--svg", svg, exit_, every], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            rows = {line.split()[0]: line.split() for line in r.stdout.splitlines()[1:] if line.split()[0].isdigit() or line.startswith("     all")}
            self.assertEqual(rows["0"][1:5], ["2", "0.0", "1.0", "-1.0"])  # ages 0 at t 0 and 3
            self.assertEqual(rows["1"][1:5], ["1", "2.0", "1.0", "+1.0"])  # age 1 at t 1 (t 4 unpaired)
            self.assertEqual(rows["2"][1:5], ["1", "4.0", "1.0", "+3.0"])
            self.assertEqual(rows["all"][1:5], ["4", "1.5", "1.0", "+0.5"])
            with open(svg) as f:
                self.assertIn("age 2: +3.0 mm, 1 poses", f.read())
            r = subprocess.run([sys.executable, MASK_AGE, exit_], capture_output=True, text=True)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("mask_age.py", r.stderr)

    def test_odd_argument_count_prints_usage(self):
        r = self.run_paired("only-one.json")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("paired.py A.json B.json", r.stderr)


if __name__ == "__main__":
    unittest.main()
