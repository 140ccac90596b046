"""benchmarks/training/paired.py: two pose nets compared recording by recording, on eval
JSON files whose differences are known by hand. Standard library only.

Run: /usr/bin/python3 -m unittest discover -s weights_tools/tests"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PAIRED = os.path.join(ROOT, "benchmarks", "training", "paired.py")


def write_eval(path, scenes):
    with open(path, "w") as f:
        json.dump({"by_condition": {"scene": {k: {"mpjpe_mm": v, "frames": 96} for k, v in scenes.items()}}}, f)


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

    def test_odd_argument_count_prints_usage(self):
        r = self.run_paired("only-one.json")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("paired.py A.json B.json", r.stderr)


if __name__ == "__main__":
    unittest.main()
