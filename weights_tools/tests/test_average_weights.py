"""benchmarks/training/average_weights.py: the mean of weights files, on tensors whose mean
is known by hand. Needs h5py and numpy.

Run: /usr/bin/python3 -m unittest discover -s weights_tools/tests"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)
SCRIPT = os.path.join(ROOT, "benchmarks", "training", "average_weights.py")
MISSING = [m for m in ("h5py", "numpy") if importlib.util.find_spec(m) is None]
if not MISSING:
    import numpy as np

    from weights_tools.h5weights import read_weights, write_weights


def setUpModule():
    if MISSING:
        raise unittest.SkipTest(f"not importable under {sys.executable}: {', '.join(MISSING)}")


def groups(scale, bn_count, conv_shape=(2, 3)):
    return {"mask": {"conv.weight": np.full(conv_shape, scale, np.float32),
                     "bn.running_var": np.array([scale, 2 * scale], np.float32),
                     "bn.num_batches_tracked": np.array(bn_count, np.float32)},
            "pose": {"fc.weight": np.array([scale], np.float32)}}


class AverageWeightsTest(unittest.TestCase):
    def average(self, d, *files, extra=()):
        out = os.path.join(d, "out.h5")
        r = subprocess.run([sys.executable, SCRIPT, out, *files, *extra], capture_output=True, text=True)
        return r, out

    def write(self, d, name, g):
        path = os.path.join(d, name)
        write_weights(path, json.dumps({"name": name}), g)
        return path

    def test_mask_group_averaged_the_rest_the_first_files(self):
        with tempfile.TemporaryDirectory() as d:
            a, b, c = (self.write(d, f"{n}.h5", groups(s, k)) for n, s, k in (("a", 1, 10), ("b", 2, 20), ("c", 6, 30)))
            r, out = self.average(d, a, b, c)
            self.assertEqual(r.returncode, 0, r.stderr)
            cfg, got = read_weights(out)
            self.assertEqual(cfg["name"], "a.h5")
            np.testing.assert_array_equal(got["mask"]["conv.weight"], np.full((2, 3), 3, np.float32))
            np.testing.assert_array_equal(got["mask"]["bn.running_var"], np.array([3, 6], np.float32))
            self.assertEqual(float(got["mask"]["bn.num_batches_tracked"]), 10)
            np.testing.assert_array_equal(got["pose"]["fc.weight"], np.array([1], np.float32))
            r, out = self.average(d, a, b, extra=("--groups", "mask,pose"))
            self.assertEqual(r.returncode, 0, r.stderr)
            np.testing.assert_array_equal(read_weights(out)[1]["pose"]["fc.weight"], np.array([1.5], np.float32))

    def test_mismatched_files_are_refused_and_nothing_is_written(self):
        with tempfile.TemporaryDirectory() as d:
            a = self.write(d, "a.h5", groups(1, 1))
            wide = self.write(d, "wide.h5", groups(1, 1, conv_shape=(2, 4)))
            r, out = self.average(d, a, wide)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("wide.h5: /mask/conv.weight has shape", r.stderr)
            self.assertFalse(os.path.exists(out))
            r, _ = self.average(d, a)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("at least two", r.stderr)


if __name__ == "__main__":
    unittest.main()
