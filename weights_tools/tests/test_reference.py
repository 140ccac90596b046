"""Tests of the PyTorch reference networks and the HDF5 converters.

Run: /usr/bin/python3 -m unittest discover -s weights_tools/tests
(Debian's python3-torch imports only under /usr/bin/python3.)"""
import json
import os
import sys
import tempfile
import time
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

try:
    import torch
    import h5py
    import numpy as np
    MISSING = None
except ImportError as e:  # pragma: no cover
    MISSING = str(e)


def setUpModule():
    if MISSING:
        banner = "!" * 78
        sys.stderr.write(f"\n{banner}\nSKIPPING weights_tools tests: {MISSING} under "
                         f"{sys.executable}.\nRun them with /usr/bin/python3 (Debian's "
                         f"python3-torch, python3-h5py).\n{banner}\n")
        raise unittest.SkipTest(f"PyTorch/h5py not importable: {MISSING}")


def _tools():
    from weights_tools import reference, h5weights, checkpoints
    from weights_tools import export_h5, import_h5, make_parity_case, make_manifest
    return reference, h5weights, checkpoints, export_h5, import_h5, make_parity_case, make_manifest


def _count(net):
    return sum(p.numel() for p in net.parameters())


def _cfg(**changes):
    """tiny.json with some fields changed: {'pose.convlstm': 'causal'}."""
    from weights_tools.reference.config import config_from_dict, CONFIG_DIR
    with open(os.path.join(CONFIG_DIR, "tiny.json")) as f:
        d = json.load(f)
    for path, v in changes.items():
        sec, key = path.split(".")
        d.setdefault(sec, {})[key] = v
    return config_from_dict(d)


class ParameterCounts(unittest.TestCase):
    def test_paper_pose_net_has_the_papers_parameter_count(self):
        ref = _tools()[0]
        cfg = ref.load_config("paper")
        self.assertEqual(_count(ref.PoseNet(cfg)), 20_390_199)
        self.assertEqual(_count(ref.MaskNet(cfg)), 31_196_768)

    def test_paper_state_dict_keys_and_shapes_match_the_reference(self):
        ref = _tools()[0]
        cfg = ref.load_config("paper")
        pose = {k: tuple(v.shape) for k, v in ref.PoseNet(cfg).state_dict().items()}
        mask = {k: tuple(v.shape) for k, v in ref.MaskNet(cfg).state_dict().items()}
        self.assertEqual(len(pose), 1774)
        self.assertEqual(len(mask), 124)
        # Keys and shapes the reference code produces (sad_pose.py, convlstm.py, unet.py,
        # nn_helpers.py, torchvision resnet34), written out by hand.
        expect_pose = {
            "in_cnn.0.weight": (64, 6, 7, 7),
            "in_cnn.1.num_batches_tracked": (),
            "in_cnn.4.2.bn2.running_var": (64,),
            "in_cnn.5.0.downsample.0.weight": (128, 64, 1, 1),
            "in_cnn.5.3.conv2.weight": (128, 128, 3, 3),
            "cl.cell_list.0.conv.weight": (512, 256, 3, 3),
            "cl.cell_list.0.conv.bias": (512,),
            "cl.fuse_list.0.weight": (128, 256, 1, 1),
            "cl.fuse_list.0.bias": (128,),
            "cl_skip_block.module.0.weight": (128, 256, 3, 3),
            "cl_skip_block.shortcut.0.weight": (128, 256, 1, 1),
            "xy_hm_cnns.0.down_layers.0.module.0.weight": (64, 128, 3, 3),
            "xy_hm_cnns.0.down_layers.2.shortcut.0.weight": (128, 64, 1, 1),
            "zy_hm_cnns.1.up_layers.2.module.0.weight": (128, 64, 3, 3),  # transposed: in, out
            "xz_hm_cnns.2.up_layers.2.shortcut.0.weight": (128, 64, 1, 1),
            "xz_hm_cnns.2.up_layers.4.module.3.weight": (13, 13, 3, 3),
            "hm_combiners.0.combine_block.module.0.weight": (128, 39, 3, 3),
            "hm_combiners.1.combine_block.shortcut.1.running_mean": (128,),
        }
        expect_mask = {
            "inc.double_conv.0.weight": (64, 6, 3, 3),
            "inc.double_conv.4.running_var": (64,),
            "down4.maxpool_conv.1.double_conv.3.weight": (1024, 1024, 3, 3),
            "up1.up.weight": (1024, 512, 2, 2),
            "up1.up.bias": (512,),
            "up1.conv.double_conv.0.weight": (512, 1024, 3, 3),
            "up4.conv.double_conv.3.weight": (64, 64, 3, 3),
            "outc.conv.weight": (16, 64, 1, 1),
            "score_conv.0.weight": (256, 64, 1, 1),
            "score_conv.1.bias": (512,),
            "fc.weight": (16, 512),
        }
        for k, s in expect_pose.items():
            self.assertEqual(pose.get(k), s, k)
        for k, s in expect_mask.items():
            self.assertEqual(mask.get(k), s, k)
        self.assertNotIn("hm_combiners.2.combine_block.module.0.weight", pose)
        self.assertNotIn("xy_hm_cnns.3.down_layers.0.module.0.weight", pose)

    def test_scaled_configs_count(self):
        ref = _tools()[0]
        small = ref.load_config("small")
        self.assertEqual((small.height, small.width), (130, 173))
        self.assertEqual(_count(ref.PoseNet(small)), 946_202)
        self.assertEqual(_count(ref.MaskNet(small)), 1_954_736)
        # Causal ConvLSTM: the fuse conv takes h channels, not 2h.
        sd = ref.PoseNet(small).state_dict()
        self.assertEqual(tuple(sd["cl.fuse_list.0.weight"].shape), (32, 32, 1, 1))

    def test_mask_role_defaults_and_checks_as_the_cpp_reader(self):
        from weights_tools.reference.config import ConfigError
        self.assertEqual(_cfg().mask_role, "mask")
        self.assertEqual(_cfg(**{"pose.masked_input": False}).mask_role, "none")
        self.assertEqual(_cfg(**{"pose.masked_input": False, "mask.role": "presence"}).mask_role, "presence")
        with self.assertRaisesRegex(ConfigError, "mask.role mask goes with pose.masked_input true"):
            _cfg(**{"mask.role": "presence"})
        with self.assertRaisesRegex(ConfigError, "mask.role must be mask, presence or none"):
            _cfg(**{"pose.masked_input": False, "mask.role": "crop"})

    def test_mask_crop_margin_is_read_and_checked_as_the_cpp_reader(self):
        from weights_tools.reference.config import ConfigError
        self.assertEqual(_cfg().mask_crop_margin, 0)
        self.assertEqual(_cfg(**{"mask.crop_margin": 8}).mask_crop_margin, 8)
        with self.assertRaisesRegex(ConfigError, r"mask.crop_margin must lie in 0..4096"):
            _cfg(**{"mask.crop_margin": -1})

    def test_run_settings_are_checked_as_the_cpp_reader_checks_them(self):
        from weights_tools.reference.config import ConfigError
        _cfg(**{"run.mask_cut": 0.5, "run.mask_cut_reused": 0.2, "run.idle_recheck_s": 0.06})
        with self.assertRaisesRegex(ConfigError, r"run.mask_cut_reused must be in \(0, 1\)"):
            _cfg(**{"run.mask_cut_reused": 1.0})
        with self.assertRaisesRegex(ConfigError, r"run.idle_recheck_s must lie in 0..1"):
            _cfg(**{"run.idle_recheck_s": -0.5})

    def test_stored_manifests_are_up_to_date(self):
        mm = _tools()[6]
        self.assertEqual(mm.main(["--check"]), 0, "run weights_tools/make_manifest.py")


class Shapes(unittest.TestCase):
    def test_paper_pose_heads_one_frame(self):
        ref = _tools()[0]
        net = ref.PoseNet(ref.load_config("paper")).eval()
        with torch.no_grad():
            heatmaps, joints = net(torch.rand(1, 6, 260, 346))
        self.assertEqual(len(heatmaps), 3)
        for planes in heatmaps:
            for hm in planes:
                self.assertEqual(tuple(hm.shape), (1, 13, 33, 44))
        self.assertEqual(tuple(joints.shape), (1, 13, 3))

    def test_tiny_heads_and_odd_sizes(self):
        ref = _tools()[0]
        cfg = ref.load_config("tiny")
        self.assertEqual((cfg.height, cfg.width), (37, 75))
        mask, pose = ref.build_networks(cfg)
        x = torch.rand(cfg.window, 6, 37, 75)
        start = time.perf_counter()
        with torch.no_grad():
            masks, scores = mask(x)
            heatmaps, joints = pose(x)
        elapsed = time.perf_counter() - start
        self.assertLess(elapsed, 5.0, "the tiny config is meant for quick tests")
        self.assertEqual(tuple(masks.shape), (3, 4, 37, 75))
        self.assertEqual(tuple(scores.shape), (3, 4))
        self.assertTrue(bool(((scores > 0) & (scores < 1)).all()))
        self.assertEqual(len(heatmaps), 2)
        # 37x75 -> conv1 19x38 -> maxpool 10x19 -> layer2 5x10
        for planes in heatmaps:
            for hm in planes:
                self.assertEqual(tuple(hm.shape), (3, 13, 5, 10))
                sums = hm.sum(dim=(2, 3))
                self.assertTrue(torch.allclose(sums, torch.ones_like(sums), atol=1e-5))
        self.assertEqual(tuple(joints.shape), (3, 13, 3))
        self.assertTrue(bool((joints.abs() < 1).all()))

    def test_head_stride_4_keeps_the_parameters_and_doubles_the_heatmaps(self):
        from weights_tools.reference.config import ConfigError
        ref = _tools()[0]
        coarse, fine = ref.PoseNet(_cfg()), ref.PoseNet(_cfg(**{"pose.head_stride": 4}))
        self.assertEqual({k: v.shape for k, v in coarse.state_dict().items()},
                         {k: v.shape for k, v in fine.state_dict().items()})
        with torch.no_grad():
            heatmaps, _ = fine.eval()(torch.rand(3, 6, 37, 75))
        # 37x75 -> conv1 19x38 -> maxpool 10x19, which layer2 keeps
        self.assertEqual(tuple(heatmaps[-1][0].shape), (3, 13, 10, 19))
        with self.assertRaisesRegex(ConfigError, "pose.head_stride must be 8 or 4"):
            _cfg(**{"pose.head_stride": 2})

    def test_batch_of_windows_equals_windows_one_by_one(self):
        ref = _tools()[0]
        cfg = ref.load_config("tiny")
        pose = ref.PoseNet(cfg).eval()
        x = torch.rand(2, cfg.window, 6, 37, 75)
        with torch.no_grad():
            _, both = pose(x)
            _, first = pose(x[0])
            _, second = pose(x[1])
        self.assertTrue(torch.allclose(both, torch.cat([first, second]), atol=1e-6))


class Temporal(unittest.TestCase):
    def _sensitivity(self, cfg):
        """For each output frame, whether it changes when the last input frame changes."""
        ref = _tools()[0]
        torch.manual_seed(0)
        pose = ref.PoseNet(cfg).eval()
        x = torch.rand(cfg.window, 6, cfg.height, cfg.width)
        y = x.clone()
        y[-1] += 1.0
        with torch.no_grad():
            _, a = pose(x)
            _, b = pose(y)
        return [(a[t] - b[t]).abs().max().item() > 0 for t in range(cfg.window)]

    def test_causal_frames_do_not_see_the_future(self):
        self.assertEqual(self._sensitivity(_cfg(**{"pose.convlstm": "causal"})), [False, False, True])

    def test_bidirectional_frames_see_the_whole_window(self):
        self.assertEqual(self._sensitivity(_cfg()), [True, True, True])


class Dsnt(unittest.TestCase):
    def test_one_hot_maps_give_pixel_centres(self):
        from weights_tools.reference.dsnt import dsnt, joints_from_heatmaps
        hm = torch.zeros(1, 2, 3, 4)
        hm[0, 0, 0, 0] = 1      # top-left: x = -(4-1)/4, y = -(3-1)/3
        hm[0, 1, 2, 1] = 1      # x = -3/4 + 2/4 = -1/4, y = +2/3
        got = dsnt(hm)[0]
        self.assertTrue(torch.allclose(got, torch.tensor([[-0.75, -2 / 3], [-0.25, 2 / 3]])))
        uniform = torch.full((1, 1, 5, 7), 1 / 35)
        self.assertTrue(torch.allclose(dsnt(uniform), torch.zeros(1, 1, 2), atol=1e-6))
        # z = mean(zy's width coordinate, xz's height coordinate)
        xy = torch.zeros(1, 1, 3, 4)
        xy[0, 0, 1, 3] = 1      # x = 0.75, y = 0
        zy = torch.zeros(1, 1, 3, 4)
        zy[0, 0, 0, 2] = 1      # width coordinate 0.25
        xz = torch.zeros(1, 1, 3, 4)
        xz[0, 0, 2, 0] = 1      # height coordinate 2/3
        j = joints_from_heatmaps(xy, zy, xz)[0, 0]
        self.assertTrue(torch.allclose(j, torch.tensor([0.75, 0.0, (0.25 + 2 / 3) / 2])))


class RoundTrip(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name
        ref, *_ = _tools()
        mpc = _tools()[5]
        self.cfg = ref.load_config("tiny")
        self.mask, self.pose, _, _ = mpc.build_case(self.cfg, 11)

    def tearDown(self):
        self.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.dir, name)

    def assert_same(self, a, b):
        self.assertEqual(sorted(a), sorted(b))
        for k in a:
            self.assertEqual(a[k].dtype, b[k].dtype, k)
            self.assertTrue(torch.equal(a[k], b[k]), k)

    def test_lightning_checkpoint_round_trip_is_exact(self):
        _, h5w, _, export_h5, import_h5, _, _ = _tools()
        # As the reference trains it: the pose net holds its frozen U-Net as mask_net, and
        # Lightning prefixes everything with `model.`.
        sd = {f"model.{k}": v for k, v in self.pose.state_dict().items()}
        sd.update({f"model.mask_net.{k}": v for k, v in self.mask.state_dict().items()})
        torch.save({"epoch": 3, "state_dict": sd, "hyper_parameters": {"n_stages": 2}},
                   self.path("pose.ckpt"))
        self.assertEqual(export_h5.main(["--config", "tiny", self.path("pose.ckpt"),
                                         "-o", self.path("w.h5")]), 0)
        with h5py.File(self.path("w.h5")) as f:
            self.assertEqual(f.attrs["format"], "yelan-weights")
            self.assertEqual(int(f.attrs["version"]), 1)
            self.assertEqual(json.loads(f.attrs["config"])["name"], "tiny")
            self.assertEqual(len(f["pose"]), 1216)
            self.assertEqual(f["pose/in_cnn.1.num_batches_tracked"].dtype, np.float32)
            self.assertEqual(f["pose/in_cnn.1.num_batches_tracked"].shape, ())
            self.assertEqual(f["mask/up1.up.weight"].shape, (128, 64, 2, 2))
        self.assertEqual(import_h5.main([self.path("w.h5"), "-o", self.path("back.pt")]), 0)
        back = torch.load(self.path("back.pt"))
        self.assert_same(back["pose"], self.pose.state_dict())
        self.assert_same(back["mask"], self.mask.state_dict())
        # And once more through our own combined .pt: same bytes of data.
        self.assertEqual(export_h5.main(["--config", "tiny", self.path("back.pt"),
                                         "-o", self.path("w2.h5")]), 0)
        _, g1 = h5w.read_weights(self.path("w.h5"))
        _, g2 = h5w.read_weights(self.path("w2.h5"))
        for g in g1:
            for k in g1[g]:
                self.assertTrue(np.array_equal(g1[g][k], g2[g][k]))

    def test_checkpoint_with_classes_not_importable_here(self):
        # Lightning keeps hyper-parameters as objects of its own classes (and the reference
        # stores its torchvision backbone there): unpickling must not need them.
        import types
        mod = types.ModuleType("lightning_only_here")

        class AttributeDict(dict):
            pass

        class Backbone:
            def __init__(self):
                self.depth = 34

        for c in (AttributeDict, Backbone):
            c.__module__, c.__qualname__ = mod.__name__, c.__name__
            setattr(mod, c.__name__, c)
        sys.modules[mod.__name__] = mod
        try:
            hp = AttributeDict(n_stages=2)
            hp["in_cnn"] = Backbone()
            sd = {f"model.{k}": v for k, v in self.pose.state_dict().items()}
            torch.save({"state_dict": sd, "hyper_parameters": hp}, self.path("pose.ckpt"))
        finally:
            del sys.modules[mod.__name__]
        torch.save(self.mask.state_dict(), self.path("mask.pt"))
        _, _, _, export_h5, import_h5, _, _ = _tools()
        self.assertEqual(export_h5.main(["--config", "tiny", "--pose", self.path("pose.ckpt"),
                                         "--mask", self.path("mask.pt"), "-o",
                                         self.path("w.h5")]), 0)
        self.assertEqual(import_h5.main([self.path("w.h5"), "--group", "pose", "-o",
                                         self.path("p.pt")]), 0)
        self.assert_same(torch.load(self.path("p.pt")), self.pose.state_dict())

    def test_bare_state_dicts_and_group_import(self):
        _, _, _, export_h5, import_h5, _, _ = _tools()
        torch.save(self.pose.state_dict(), self.path("pose.pt"))
        torch.save({f"module.{k}": v for k, v in self.mask.state_dict().items()},
                   self.path("mask.pt"))
        self.assertEqual(export_h5.main(["--config", "tiny", "--pose", self.path("pose.pt"),
                                         "--mask", self.path("mask.pt"), "-o",
                                         self.path("w.h5")]), 0)
        self.assertEqual(import_h5.main([self.path("w.h5"), "--group", "mask", "-o",
                                         self.path("m.pt")]), 0)
        self.assert_same(torch.load(self.path("m.pt")), self.mask.state_dict())

    def _export_error(self, pose_sd, capsys_args=()):
        _, _, _, export_h5, _, _, _ = _tools()
        torch.save(pose_sd, self.path("pose.pt"))
        torch.save(self.mask.state_dict(), self.path("mask.pt"))
        import io
        from contextlib import redirect_stderr
        err = io.StringIO()
        with redirect_stderr(err):
            rc = export_h5.main(["--config", "tiny", "--pose", self.path("pose.pt"), "--mask",
                                 self.path("mask.pt"), "-o", self.path("w.h5"), *capsys_args])
        self.assertFalse(os.path.exists(self.path("w.h5")))
        self.assertEqual([f for f in os.listdir(self.dir) if ".tmp-" in f], [])
        return rc, err.getvalue()

    def test_export_names_missing_unexpected_and_misshaped_tensors(self):
        sd = dict(self.pose.state_dict())
        del sd["cl.fuse_list.0.bias"]
        sd["cl.extra.weight"] = torch.zeros(3)
        sd["in_cnn.0.weight"] = torch.zeros(8, 6, 7, 5)
        rc, err = self._export_error(sd)
        self.assertEqual(rc, 2)
        self.assertIn("1 missing: cl.fuse_list.0.bias", err)
        self.assertIn("1 unexpected: cl.extra.weight", err)
        self.assertIn("in_cnn.0.weight: shape [8, 6, 7, 5], expected [8, 6, 7, 7]", err)

    def test_export_refuses_float64_unless_asked(self):
        sd = {k: (v.double() if v.is_floating_point() else v) for k, v in self.pose.state_dict().items()}
        rc, err = self._export_error(sd)
        self.assertEqual(rc, 2)
        self.assertIn("dtype torch.float64; float32 expected (--allow-downcast", err)

    def test_import_rejects_foreign_and_damaged_files(self):
        _, h5w, _, export_h5, import_h5, _, _ = _tools()
        torch.save(self.pose.state_dict(), self.path("pose.pt"))
        torch.save(self.mask.state_dict(), self.path("mask.pt"))
        export_h5.main(["--config", "tiny", "--pose", self.path("pose.pt"), "--mask",
                        self.path("mask.pt"), "-o", self.path("w.h5")])
        cases = []
        with h5py.File(self.path("w.h5"), "a") as f:
            del f["pose/cl.fuse_list.0.bias"]
        cases.append(("missing", "(pose): 1 missing: cl.fuse_list.0.bias"))
        with open(self.path("junk.h5"), "wb") as f:
            f.write(b"not hdf5 at all")
        with h5py.File(self.path("fmt.h5"), "w") as f:
            f.attrs["format"] = "yelan-recording"
        with h5py.File(self.path("f64.h5"), "w") as f:
            f.attrs["format"] = "yelan-weights"
            f.attrs["version"] = 1
            f.attrs["config"] = json.dumps(self.cfg.raw)
            f.create_group("mask").create_dataset("fc.bias", data=np.zeros(4))
            f.create_group("pose")
        expect = {
            "w.h5": "(pose): 1 missing: cl.fuse_list.0.bias",
            "junk.h5": "not an HDF5 file",
            "fmt.h5": "root attribute format is 'yelan-recording', expected 'yelan-weights'",
            "f64.h5": "/mask/fc.bias has type float64, expected float32",
            "absent.h5": "no such file",
        }
        with self.assertRaises(h5w.WeightsError):
            import_h5.state_dicts_from_h5(self.path("absent.h5"))
        for name, msg in expect.items():
            with self.assertRaises(h5w.WeightsError) as cm:
                import_h5.state_dicts_from_h5(self.path(name))
            self.assertIn(msg, str(cm.exception), name)


class ParityCase(unittest.TestCase):
    def test_case_file_layout_and_determinism(self):
        _, h5w, _, _, _, mpc, _ = _tools()
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "case.h5")
            self.assertEqual(mpc.main(["--config", "tiny", "--seed", "5", "-o", out]), 0)
            with h5py.File(out) as f:
                names = set()
                f.visititems(lambda n, o: names.add(n) if isinstance(o, h5py.Dataset) else None)
                want = {"input", "masks", "scores", "joints_norm"}
                want |= {f"heatmaps/stage{i}/{p}" for i in range(2) for p in ("xy", "zy", "xz")}
                self.assertEqual(names, want)
                self.assertEqual(f["input"].shape, (3, 6, 37, 75))
                self.assertEqual(f["masks"].shape, (3, 4, 37, 75))
                self.assertEqual(f["heatmaps/stage1/xz"].shape, (3, 13, 5, 10))
                self.assertEqual(f.attrs["weights_file"], "case.weights.h5")
                # Not degenerate: heatmaps neither uniform nor one-hot.
                hm = f["heatmaps/stage1/xy"][()]
                self.assertGreater(hm.max(), 2.0 / 50)
                self.assertLess(np.median(hm.max(axis=(2, 3))), 0.99)
                first = {n: f[n][()] for n in names}
            # The weights reproduce the outputs.
            ref = _tools()[0]
            cfg = ref.load_config("tiny")
            _, groups = h5w.read_weights(os.path.join(d, "case.weights.h5"))
            pose = ref.PoseNet(cfg)
            pose.load_state_dict({k: torch.tensor(v) if not k.endswith("tracked") else
                                  torch.tensor(int(v)) for k, v in groups["pose"].items()})
            with torch.no_grad():
                _, joints = pose.eval()(torch.from_numpy(first["input"]))
            self.assertTrue(np.allclose(joints.numpy(), first["joints_norm"], atol=1e-6))
            self.assertEqual(mpc.main(["--config", "tiny", "--seed", "5", "-o", out]), 0)
            with h5py.File(out) as f:
                for n, v in first.items():
                    self.assertTrue(np.array_equal(f[n][()], v), n)


if __name__ == "__main__":
    unittest.main()
