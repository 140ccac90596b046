"""Model configurations: the JSON files in weights_tools/configs/ (stored verbatim in the
root attribute `config` of a weights file)."""
import json
import math
import os
from dataclasses import dataclass

CONFIG_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "configs")

CONVLSTM_MODES = ("bidirectional", "causal", "none")
REPRESENTATIONS = ("tore", "counts")


class ConfigError(ValueError):
    pass


def _scaled(base, mult):
    # Channel counts are rounded to the nearest integer, never below 1.
    return max(1, int(round(base * mult)))


@dataclass(frozen=True)
class ModelConfig:
    name: str
    channels: int          # TORE channels C (2K)
    sensor_height: int
    sensor_width: int
    downscale: int         # network input is (sensor_h // d, sensor_w // d)
    window: int            # S, frames per window of the pose net
    mask_width: float      # width multiplier of the U-Net (64..1024 at 1.0)
    n_masks: int           # N: current + N-1 future masks
    pose_width: float      # width multiplier of ResNet head and hourglasses (64/128 at 1.0)
    hidden: int            # ConvLSTM hidden channels
    stages: int
    joints: int
    convlstm: str          # bidirectional | causal | none (the skip block sees the head alone)
    raw: dict
    masked_input: bool = True      # False: stage 2 reads the whole input
    outside_input: bool = False    # stage 2 reads [inside the mask | outside it]: 2 x channels
    mask_role: str = "mask"        # mask | presence (stage 1 only says whether anyone is there) | none
    crop_margin: int = 0           # inference only (C++ PoseNet::forward_cropped); 0: whole frame
    mask_crop_margin: int = 0      # inference only (C++ MaskNet::forward_cropped); 0: whole frame
    head_stride: int = 8           # the ResNet head's stride: 8, or 4 (layer2 keeps layer1's resolution)
    hourglass_skip: bool = False   # each hourglass adds its second block's output to its up block's
    depth_map: bool = False        # a fourth hourglass per stage: depth maps read under the xy maps give z
    representation: str = "tore"   # or "counts": log(1 + events) per polarity per frame period
    mask_pool: int = 1             # stage 1 on the input avg-pooled k x k, its logits resized back bilinearly              # the JSON object this was read from

    @property
    def height(self):
        return self.sensor_height // self.downscale

    @property
    def width(self):
        return self.sensor_width // self.downscale

    # Channel widths derived from the multipliers.
    def unet_widths(self):
        return [_scaled(b, self.mask_width) for b in (64, 128, 256, 512, 1024)]

    def resnet_widths(self):
        return _scaled(64, self.pose_width), _scaled(128, self.pose_width)

    def hourglass_widths(self):
        return _scaled(64, self.pose_width), _scaled(128, self.pose_width)

    def to_json(self):
        return json.dumps(self.raw, sort_keys=True, separators=(",", ":"))


def _get(obj, path, key, kind, default=None):
    if key not in obj:
        if default is not None:
            return default
        raise ConfigError(f"{path}: missing key '{key}'")
    v = obj[key]
    if kind is int and (isinstance(v, bool) or not isinstance(v, int)):
        raise ConfigError(f"{path}.{key}: expected an integer, got {v!r}")
    if kind is float and (isinstance(v, bool) or not isinstance(v, (int, float))):
        raise ConfigError(f"{path}.{key}: expected a number, got {v!r}")
    if kind is str and not isinstance(v, str):
        raise ConfigError(f"{path}.{key}: expected a string, got {v!r}")
    return kind(v)


def _get_bool(obj, path, key, default):
    if key not in obj:
        return default
    if not isinstance(obj[key], bool):
        raise ConfigError(f"{path}.{key}: expected true or false, got {obj[key]!r}")
    return obj[key]


def config_from_dict(d, where="config"):
    if not isinstance(d, dict):
        raise ConfigError(f"{where}: expected a JSON object")
    for sec in ("input", "mask", "pose"):
        if not isinstance(d.get(sec), dict):
            raise ConfigError(f"{where}: missing object '{sec}'")
    i, m, p = d["input"], d["mask"], d["pose"]
    # One line per key, as the C++ reader (engine/model_config.cpp) checks them: a table, deliberately spelled out.
    cfg = ModelConfig(
        name=_get(d, where, "name", str),
        channels=_get(i, where + ".input", "channels", int),
        sensor_height=_get(i, where + ".input", "sensor_height", int),
        sensor_width=_get(i, where + ".input", "sensor_width", int),
        downscale=_get(i, where + ".input", "downscale", int),
        window=_get(i, where + ".input", "window", int),
        mask_width=_get(m, where + ".mask", "width_mult", float),
        n_masks=_get(m, where + ".mask", "n_masks", int),
        pose_width=_get(p, where + ".pose", "width_mult", float),
        hidden=_get(p, where + ".pose", "hidden", int),
        stages=_get(p, where + ".pose", "stages", int),
        joints=_get(p, where + ".pose", "joints", int),
        convlstm=_get(p, where + ".pose", "convlstm", str),
        raw=d,
        masked_input=_get_bool(p, where + ".pose", "masked_input", True),
        outside_input=_get_bool(p, where + ".pose", "outside_input", False),
        crop_margin=_get(p, where + ".pose", "crop_margin", int, 0),
        mask_crop_margin=_get(m, where + ".mask", "crop_margin", int, 0),
        head_stride=_get(p, where + ".pose", "head_stride", int, 8),
        hourglass_skip=_get_bool(p, where + ".pose", "hourglass_skip", False),
        depth_map=_get_bool(p, where + ".pose", "depth_map", False),
        representation=_get(i, where + ".input", "representation", str, "tore"),
        mask_pool=_get(m, where + ".mask", "pool", int, 1),
        mask_role=_get(m, where + ".mask", "role", str,
                       "mask" if _get_bool(p, where + ".pose", "masked_input", True) else "none"),
    )
    # run (optional): how `yelan run` uses the model (beta, presence calibration); checked
    # here as in engine/model_config.cpp, used only by the C++ runtime.
    run = d.get("run", {})
    if not isinstance(run, dict):
        raise ConfigError(f"{where}: missing object 'run'")
    beta = _get(run, where + ".run", "beta", float, 0.99)
    depth_scale = _get(run, where + ".run", "depth_scale", float, 1.0)
    mask_cut = _get(run, where + ".run", "mask_cut", float, 0.1)
    mask_cut_reused = _get(run, where + ".run", "mask_cut_reused", float, mask_cut)
    idle_recheck_s = _get(run, where + ".run", "idle_recheck_s", float, 0.0)
    pa, pb = 3.0, 13.8
    if "presence" in run:
        if not isinstance(run["presence"], dict):
            raise ConfigError(f"{where}.run: missing object 'presence'")
        pa = _get(run["presence"], where + ".run.presence", "a", float)
        pb = _get(run["presence"], where + ".run.presence", "b", float)
    checks = [
        (0 <= beta <= 2, "run.beta must be in 0..2 (above 1: stage 1 on every tick)"),
        (0 < depth_scale <= 1000, "run.depth_scale must be in (0, 1000]"),
        (0 < mask_cut < 1, "run.mask_cut must be in (0, 1)"),
        (0 < mask_cut_reused < 1, "run.mask_cut_reused must be in (0, 1)"),
        (0 <= idle_recheck_s <= 1, "run.idle_recheck_s must lie in 0..1 (seconds)"),
        (math.isfinite(pa) and math.isfinite(pb) and pa >= 0, "run.presence: a must be finite and >= 0, b finite"),
        (cfg.channels >= 1, "input.channels must be >= 1"),
        (cfg.downscale >= 1, "input.downscale must be >= 1"),
        (cfg.window >= 1, "input.window must be >= 1"),
        (cfg.crop_margin >= 0, "pose.crop_margin must be >= 0"),
        (0 <= cfg.mask_crop_margin <= 4096, "mask.crop_margin must lie in 0..4096 (input pixels; 0: the whole frame)"),
        (cfg.head_stride in (8, 4), "pose.head_stride must be 8 or 4"),
        (cfg.mask_role in ("mask", "presence", "none"), "mask.role must be mask, presence or none"),
        ((cfg.mask_role == "mask") == cfg.masked_input,
         "mask.role mask goes with pose.masked_input true, presence and none with false"),
        (not cfg.outside_input or cfg.masked_input, "pose.outside_input needs pose.masked_input (a mask to be outside of)"),
        (not cfg.outside_input or 2 * cfg.channels <= 16, "pose.outside_input needs input.channels <= 8 (one channel block)"),
        (cfg.mask_width > 0 and cfg.pose_width > 0, "width_mult must be > 0"),
        (cfg.n_masks >= 1 and cfg.hidden >= 1 and cfg.stages >= 1 and cfg.joints >= 1,
         "n_masks, hidden, stages and joints must be >= 1"),
        (cfg.convlstm in CONVLSTM_MODES, f"pose.convlstm must be one of {CONVLSTM_MODES}"),
        (cfg.representation in REPRESENTATIONS, "input.representation must be tore or counts"),
        (cfg.representation != "tore" or cfg.channels % 2 == 0, "input.channels must be even for TORE (2K planes)"),
        (cfg.representation != "counts" or cfg.channels == 2, "input.channels must be 2 for counts (one per polarity)"),
        # The U-Net pools 4 times and the pose net divides by 16 before the hourglass.
        (cfg.height >= 16 and cfg.width >= 16, "input is smaller than 16 x 16 after downscale"),
        (1 <= cfg.mask_pool <= 8, "mask.pool must be in 1..8"),
        (cfg.height // max(cfg.mask_pool, 1) >= 16 and cfg.width // max(cfg.mask_pool, 1) >= 16,
         "stage 1's input is smaller than 16 x 16 after mask.pool"),
    ]
    for ok, msg in checks:
        if not ok:
            raise ConfigError(f"{where}: {msg}")
    return cfg


def load_config(name_or_path):
    """A config by name (weights_tools/configs/NAME.json) or by path."""
    path = name_or_path
    if not os.path.exists(path):
        path = os.path.join(CONFIG_DIR, name_or_path + ".json")
    if not os.path.exists(path):
        raise ConfigError(f"no config '{name_or_path}' (not a file, not in {CONFIG_DIR})")
    with open(path) as f:
        try:
            d = json.load(f)
        except json.JSONDecodeError as e:
            raise ConfigError(f"{path}: not valid JSON: {e}") from None
    return config_from_dict(d, path)
