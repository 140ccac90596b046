"""benchmarks/training/curves.py: the learning-curve chart from a run's log.csv and run.json.
Standard library only.

Run: /usr/bin/python3 -m unittest discover -s weights_tools/tests"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CURVES = os.path.join(ROOT, "benchmarks", "training", "curves.py")
HEADER = "step,epoch,loss,val_loss,lr,grad_norm,samples_per_s,wall_s,val_mpjpe_mm,cpu_s\n"


def make_run(folder, rows):
    os.makedirs(folder)
    with open(os.path.join(folder, "run.json"), "w") as f:
        json.dump({"config": "tiny-test", "batch": 2, "window": 4}, f)
    with open(os.path.join(folder, "log.csv"), "w") as f:
        f.write(HEADER)
        for step, mm in rows:
            f.write(f"{step},0,0.5,-1,0.001,0.1,10,{step},{mm},{step * 3.6}\n")


class CurvesTest(unittest.TestCase):
    def run_curves(self, *args):
        return subprocess.run([sys.executable, CURVES, *args], capture_output=True, text=True)

    def test_chart_marks_and_summary(self):
        with tempfile.TemporaryDirectory() as d:
            run = os.path.join(d, "r1")
            make_run(run, [(100, 300.0), (200, -1), (300, 250.0), (400, 260.0)])
            out = os.path.join(d, "c.svg")
            r = self.run_curves(run, "--out", out, "--mark", "250:new <sample>", "--csv", os.path.join(d, "c.csv"))
            self.assertEqual(r.returncode, 0, r.stderr)
            svg = open(out).read()
            # one dotted line per panel at the first validation at or after step 250 (step 300)
            self.assertEqual(svg.count('stroke-dasharray="2,3"'), 2)
            self.assertIn("new &lt;sample&gt;", svg)
            self.assertIn("best validation MPJPE 250.0 mm at step 300", r.stdout)
            self.assertIn("last 260.0 mm at step 400", r.stdout)
            rows = open(os.path.join(d, "c.csv")).read().splitlines()
            self.assertEqual(len(rows), 4)  # header and the three validated steps
            # a mark past the last validation draws nothing
            r = self.run_curves(run, "--out", out, "--mark", "999:late")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertNotIn("late", open(out).read())

    def test_bad_mark_is_a_usage_error(self):
        with tempfile.TemporaryDirectory() as d:
            run = os.path.join(d, "r1")
            make_run(run, [(100, 300.0)])
            r = self.run_curves(run, "--out", os.path.join(d, "c.svg"), "--mark", "abc")
            self.assertEqual(r.returncode, 2)
            self.assertIn("--mark 'abc': expected STEP:TEXT", r.stderr)
            self.assertFalse(os.path.exists(os.path.join(d, "c.svg")))


if __name__ == "__main__":
    unittest.main()
