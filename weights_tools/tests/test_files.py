"""Files that cross between Python and the C++ binary: the per-tensor checksum of weights
files, a recording written the ordinary h5py way, and the one temporary-file helper.
Needs h5py and numpy, not PyTorch; the cases that run the binary (YELAN_BINARY, default
build/release/yelan) skip, saying so, where it is not built.

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
MODEL = os.path.join(ROOT, "models", "default.h5")
MISSING = [m for m in ("h5py", "numpy") if importlib.util.find_spec(m) is None]
if not MISSING:
    import h5py
    import numpy as np


def setUpModule():
    if MISSING:
        raise unittest.SkipTest(f"not importable under {sys.executable}: {', '.join(MISSING)}")


def _binary():
    path = os.environ.get("YELAN_BINARY") or os.path.join(ROOT, "build", "release", "yelan")
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        raise unittest.SkipTest(f"the yelan binary is not built ({path})")
    return path


def _yelan(*args):
    return subprocess.run([_binary(), *args], capture_output=True, text=True, timeout=300)


class Scratch(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="yelan-pyfiles-")
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.dir, name)


class WeightsChecksum(Scratch):
    def test_fnv1a64_is_the_cpp_definition(self):
        from weights_tools.h5weights import tensor_checksum
        # FNV-1a's loop and prime from the C++ writer's offset basis 1469598103934665603 (not
        # the published 14695981039346656037: a digit short, kept so existing files verify);
        # by hand over 1.0f (bytes 00 00 80 3f).
        self.assertEqual(tensor_checksum(np.zeros(0, np.float32)), 1469598103934665603)
        h = 1469598103934665603
        for b in (0x00, 0x00, 0x80, 0x3f):
            h = ((h ^ b) * 0x100000001b3) % (1 << 64)
        self.assertEqual(tensor_checksum(np.array([1.0], np.float32)), h)
        self.assertEqual(tensor_checksum(np.array(1.0, ">f4")), h)  # the stored bytes: little-endian
        # Every tensor of a model the C++ writer made: the attribute it stored.
        with h5py.File(MODEL, "r") as f:
            for g in ("mask", "pose"):
                for key, ds in f[g].items():
                    self.assertEqual(int(ds.attrs["fnv1a64"]), tensor_checksum(ds[()]), f"/{g}/{key}")

    def test_python_written_weights_carry_it_and_the_binary_verifies_them(self):
        from weights_tools.h5weights import read_weights, write_weights
        cfg, groups = read_weights(MODEL)
        out = self.path("python.h5")
        write_weights(out, json.dumps(cfg, separators=(",", ":")), groups)
        self.assertEqual(sorted(os.listdir(self.dir)), ["python.h5"])  # no temporary file left
        with h5py.File(MODEL, "r") as c, h5py.File(out, "r") as p:
            for g in ("mask", "pose"):
                for key, ds in p[g].items():
                    self.assertEqual(ds.attrs["fnv1a64"].dtype, np.dtype("<u8"))
                    self.assertEqual(int(ds.attrs["fnv1a64"]), int(c[g][key].attrs["fnv1a64"]), f"/{g}/{key}")
            key = next(k for k, ds in p["pose"].items() if ds.size >= 64)
            at = p["pose"][key].id.get_offset()  # contiguous: the first data byte in the file
        self.assertIsNotNone(at)
        r = _yelan("weights", "verify", out, "--config", "small-mask0.375-pose0.125")
        self.assertEqual(r.returncode, 0, r.stderr)
        # A byte flipped inside a tensor of the Python-written file: the loader names it.
        with open(out, "r+b") as f:
            f.seek(at + 4 * 17 + 1)
            b = f.read(1)[0]
            f.seek(at + 4 * 17 + 1)
            f.write(bytes([b ^ 0x10]))
        demo = os.path.join(ROOT, "data", "demo", "lena-93_03-front-high-static.yelan.h5")
        r = _yelan("run", "--weights", out, demo, "--out", self.path("poses.csv"))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(f"tensor /pose/{key}: checksum mismatch", r.stderr)
        self.assertFalse(os.path.exists(self.path("poses.csv")))


def write_plain_recording(path, seconds=0.5):
    """A SPEC 2 recording as anyone would write it with h5py: variable-length str attributes,
    the sensor size only in /camera/{width,height}, no chunking, no root width/height."""
    rng = np.random.default_rng(5)
    n = 8000
    t = np.sort(rng.integers(0, int(seconds * 1e6), n)).astype(np.int64)
    label_t = np.arange(0, int(seconds * 1e6), 3333, dtype=np.int64)
    mask_t = np.arange(0, int(seconds * 1e6), 20000, dtype=np.int64)
    joints = np.array([[0, -580, 3500], [-190, -450, 3500], [190, -450, 3500], [-230, -140, 3530],
                       [200, -130, 3550], [-100, 110, 3510], [100, 120, 3510], [-240, 100, 3450],
                       [220, 110, 3470], [-100, 530, 3490], [90, 540, 3470], [-120, 920, 3650],
                       [75, 920, 3640]], np.float32)
    masks = np.zeros((len(mask_t), 260, 346), np.uint8)
    masks[:, 60:230, 130:220] = 1
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "yelan-recording"
        f.attrs["version"] = 1
        for k, v in (("character", "lena"), ("motion", "93_03"), ("view", "front"), ("lighting", "high"),
                     ("background", "static"), ("scene", json.dumps({"name": "plain", "occluders": False}))):
            f.attrs[k] = v  # str: h5py writes a variable-length UTF-8 string
        f.attrs["seed"] = 1
        f["camera/K"] = np.array([[485, 0, 173], [0, 485, 130], [0, 0, 1]], np.float64)
        f["camera/dist"] = np.zeros((1, 5))
        f["camera/M"] = np.hstack([np.eye(3), np.zeros((3, 1))])
        f["camera/width"] = np.int64(346)
        f["camera/height"] = np.int64(260)
        f["events/t"] = t
        f["events/x"] = rng.integers(130, 220, n).astype(np.uint16)
        f["events/y"] = rng.integers(60, 230, n).astype(np.uint16)
        f["events/p"] = rng.integers(0, 2, n).astype(np.uint8)
        f["labels/t"] = label_t
        f["labels/joints"] = np.repeat(joints[None], len(label_t), axis=0)
        f["labels/valid"] = np.ones((len(label_t), 13), np.uint8)
        f["masks/t"] = mask_t
        f["masks/data"] = masks


class PlainRecording(Scratch):
    def test_a_recording_written_the_ordinary_h5py_way_reads(self):
        os.makedirs(self.path("rec"))
        rec = self.path("rec/plain.yelan.h5")
        write_plain_recording(rec)
        with h5py.File(rec, "r") as f:  # the case this is about: variable-length strings
            self.assertTrue(h5py.check_string_dtype(f.attrs.get_id("format").dtype).length is None)
        r = _yelan("info", rec)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("346x260", r.stdout)
        self.assertIn("yelan-h5", r.stdout)
        # The recording reader too (labels, masks, the scene attributes): eval --data.
        r = _yelan("eval", "--weights", MODEL, "--data", self.path("rec"), "--seconds", "0.1", "--no-floors")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("character:  lena", r.stdout)
        self.assertIn("lighting:  high", r.stdout)


class AtomicPath(Scratch):
    def test_written_whole_or_not_at_all_never_through_a_planted_link(self):
        from weights_tools.atomic import atomic_path, write_text_atomically
        out = self.path("out.txt")
        with open(self.path("precious"), "w") as f:
            f.write("precious")
        for planted in (f"out.txt.tmp-{os.getpid()}", "out.txt.tmp"):  # the names used before
            os.symlink(self.path("precious"), self.path(planted))
        write_text_atomically(out, "whole")
        with open(out) as f:
            self.assertEqual(f.read(), "whole")
        with open(self.path("precious")) as f:
            self.assertEqual(f.read(), "precious")
        with self.assertRaises(RuntimeError):
            with atomic_path(out) as tmp:
                with open(tmp, "w") as f:
                    f.write("half")
                raise RuntimeError("failed half way")
        with open(out) as f:
            self.assertEqual(f.read(), "whole")
        left = sorted(n for n in os.listdir(self.dir) if not os.path.islink(self.path(n)))
        self.assertEqual(left, ["out.txt", "precious"])
        umask = os.umask(0)
        os.umask(umask)
        self.assertEqual(os.stat(out).st_mode & 0o777, 0o666 & ~umask)


if __name__ == "__main__":
    unittest.main()
