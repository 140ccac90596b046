"""benchmarks/training/presence_roc.py: presence detectors compared along their ROC curves,
on poses whose rates are known by hand. Standard library only.

Run: /usr/bin/python3 -m unittest discover -s weights_tools/tests"""
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROC = os.path.join(ROOT, "benchmarks", "training", "presence_roc.py")


def write_poses(path, dancers, empties):
    with open(path, "w") as f:
        f.write("source,t_us,dancer,person,confidence\n")
        for truth, confs in ((1, dancers), (0, empties)):
            for k, c in enumerate(confs):
                f.write(f"r{truth},{k},{truth},{int(c >= 0.5)},{c}\n")


class PresenceRocTest(unittest.TestCase):
    def test_rates_along_the_curve(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "p.csv")
            # Every dancer is found only where one empty pose of four (0.65) is called too;
            # no empty pose is called where three of four dancers (>= 0.7) are.
            write_poses(p, [0.9, 0.8, 0.7, 0.6], [0.65, 0.3, 0.2, 0.1])
            svg = os.path.join(d, "roc.svg")
            r = subprocess.run([sys.executable, ROC, f"m={p}", "--svg", svg], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            row = next(line.split() for line in r.stdout.splitlines() if line.startswith("m "))
            # model, poses, dancer, empty, AUC, empty@96, empty@98, dancer@2, dancer@4
            self.assertEqual(row, ["m", "8", "100.0%", "25.0%", "0.9375", "25.0%", "25.0%", "75.0%", "75.0%"])
            with open(svg) as f:
                s = f.read()
            self.assertEqual(s.count("<polyline"), 1)
            self.assertEqual(s.count("<circle"), 1)

    def test_one_class_and_bad_names_are_refused(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "p.csv")
            write_poses(p, [0.9, 0.8], [])
            r = subprocess.run([sys.executable, ROC, f"m={p}"], capture_output=True, text=True)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("needs poses with a dancer and poses of empty scenes", r.stderr)
            r = subprocess.run([sys.executable, ROC, p], capture_output=True, text=True)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("expected NAME=POSES.csv", r.stderr)


if __name__ == "__main__":
    unittest.main()
