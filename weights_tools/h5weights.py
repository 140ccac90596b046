"""Our HDF5 weights file (Python side) and matching state_dicts against a config.

Layout: root attributes format="yelan-weights", version=1, config=<JSON>; groups `mask`
and `pose`; in each, one float32 dataset per state_dict entry, named by its key, in
PyTorch's layout (num_batches_tracked as a float32 scalar)."""
import json
import os

import h5py
import numpy as np

from .atomic import atomic_path

FORMAT = "yelan-weights"
VERSION = 1
GROUPS = ("mask", "pose")
BUFFER_SUFFIXES = (".running_mean", ".running_var", ".num_batches_tracked")
# float32 holds every integer up to 2^24 exactly; beyond it the round trip would not be exact.
MAX_EXACT_COUNT = 1 << 24


class WeightsError(Exception):
    """Bad input: a message naming the file and the problem."""


def is_parameter(name):
    return not name.endswith(BUFFER_SUFFIXES)


def expected_shapes(cfg):
    """{group: {key: shape}} of the networks a config builds."""
    from .reference import MaskNet, PoseNet
    nets = {"mask": MaskNet(cfg), "pose": PoseNet(cfg)}
    return {g: {k: tuple(v.shape) for k, v in n.state_dict().items()} for g, n in nets.items()}


LISTED_NAMES = 20
LISTED_SHAPES = 10


def describe_mismatch(where, expected, got):
    """'' when the shapes of `got` equal `expected` exactly, else the differences (the first
    few of each kind: a file of another config differs in hundreds of tensors)."""
    missing = sorted(set(expected) - set(got))
    extra = sorted(set(got) - set(expected))
    wrong = sorted(k for k in set(expected) & set(got) if tuple(expected[k]) != tuple(got[k]))

    def names(v):
        more = f", ... ({len(v) - LISTED_NAMES} more)" if len(v) > LISTED_NAMES else ""
        return ", ".join(v[:LISTED_NAMES]) + more

    lines = []
    if missing:
        lines.append(f"{where}: {len(missing)} missing: {names(missing)}")
    if extra:
        lines.append(f"{where}: {len(extra)} unexpected: {names(extra)}")
    for k in wrong[:LISTED_SHAPES]:
        lines.append(f"{where}: {k}: shape {list(got[k])}, expected {list(expected[k])}")
    if len(wrong) > LISTED_SHAPES:
        lines.append(f"{where}: {len(wrong) - LISTED_SHAPES} more tensors with a wrong shape")
    return "\n".join(lines)


def to_float32(name, tensor, source, allow_downcast=False):
    """A state_dict tensor as a float32 numpy array, refusing anything not exact."""
    import torch
    t = tensor.detach().cpu()
    if name.endswith(".num_batches_tracked"):
        v = int(t.item())
        if v < 0 or v > MAX_EXACT_COUNT:
            raise WeightsError(f"{source}: {name} = {v} is not exactly representable in float32")
        return np.array(v, dtype=np.float32)
    if t.dtype in (torch.float32, torch.float16, torch.bfloat16):
        return t.to(torch.float32).numpy()
    if t.dtype == torch.float64 and allow_downcast:
        return t.to(torch.float32).numpy()
    raise WeightsError(f"{source}: {name} has dtype {t.dtype}; float32 expected"
                       + (" (--allow-downcast converts float64)" if t.dtype == torch.float64 else ""))


def _untimed_group(parent, name):
    gcpl = h5py.h5p.create(h5py.h5p.GROUP_CREATE)
    gcpl.set_obj_track_times(False)
    return h5py.Group(h5py.h5g.create(parent.id, name.encode(), gcpl=gcpl))


CHECKSUM_ATTR = "fnv1a64"
# The C++ writer's constants (weights_tools/weights_file.cpp). Its offset basis is one digit
# short of FNV's published 14695981039346656037; kept, so every file written so far verifies.
_FNV_OFFSET, _FNV_PRIME, _MASK64 = 1469598103934665603, 1099511628211, (1 << 64) - 1


def tensor_checksum(arr):
    """FNV-1a's loop (64-bit) over a tensor's float32 bytes, little-endian as stored: the
    attribute `fnv1a64` the C++ writer puts on every dataset and its loader verifies."""
    h = _FNV_OFFSET
    for b in np.ascontiguousarray(arr, dtype="<f4").tobytes():
        h = ((h ^ b) * _FNV_PRIME) & _MASK64
    return h


def write_weights(path, config_json, groups):
    """groups: {group: {key: float32 ndarray}}. Written to a temp file, then renamed."""
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w", track_order=False) as f:
            f.attrs["format"] = FORMAT
            f.attrs["version"] = np.int64(VERSION)
            f.attrs["config"] = config_json
            for g in GROUPS:
                grp = _untimed_group(f, g)
                for key in sorted(groups.get(g, {})):
                    arr = np.asarray(groups[g][key], dtype=np.float32, order="C")  # keeps 0-d as 0-d
                    ds = grp.create_dataset(key, data=arr, track_times=False)
                    ds.attrs.create(CHECKSUM_ATTR, np.uint64(tensor_checksum(arr)), dtype="<u8")


def read_weights(path):
    """-> (config dict, {group: {key: float32 ndarray}}); WeightsError on anything malformed."""
    if not os.path.exists(path):
        raise WeightsError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise WeightsError(f"{path}: not an HDF5 file ({e})") from None
    with f:
        fmt = f.attrs.get("format")
        if isinstance(fmt, bytes):
            fmt = fmt.decode()
        if fmt != FORMAT:
            raise WeightsError(f"{path}: root attribute format is {fmt!r}, expected {FORMAT!r}")
        ver = f.attrs.get("version")
        if ver is None or int(ver) != VERSION:
            raise WeightsError(f"{path}: version {ver!r} is not supported (this reads {VERSION})")
        cfg_text = f.attrs.get("config")
        if isinstance(cfg_text, bytes):
            cfg_text = cfg_text.decode()
        try:
            cfg = json.loads(cfg_text)
        except (TypeError, json.JSONDecodeError) as e:
            raise WeightsError(f"{path}: root attribute config is not JSON ({e})") from None
        out = {}
        for g in GROUPS:
            if g not in f or not isinstance(f[g], h5py.Group):
                raise WeightsError(f"{path}: group /{g} is missing")
            out[g] = {}
            for key, ds in f[g].items():
                if not isinstance(ds, h5py.Dataset):
                    raise WeightsError(f"{path}: /{g}/{key} is not a dataset")
                if ds.dtype != np.float32:
                    raise WeightsError(f"{path}: /{g}/{key} has type {ds.dtype}, expected float32")
                out[g][key] = ds[()]
        extra = sorted(set(f.keys()) - set(GROUPS))
        if extra:
            raise WeightsError(f"{path}: unexpected root objects: {', '.join(extra)}")
    return cfg, out


def manifest(cfg):
    """The names and shapes a config's weights file must hold (what C++ verifies against)."""
    shapes = expected_shapes(cfg)
    m = {"format": "yelan-weights-manifest", "version": 1, "config": cfg.raw, "groups": {},
         "parameters": {}, "tensors": {}}
    for g in GROUPS:
        m["groups"][g] = [{"name": k, "shape": list(s)} for k, s in sorted(shapes[g].items())]
        m["parameters"][g] = int(sum(int(np.prod(s)) for k, s in shapes[g].items() if is_parameter(k)))
        m["tensors"][g] = len(shapes[g])
    return m
