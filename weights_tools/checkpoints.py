"""Loading state_dicts from .pt files and Lightning checkpoints, and finding our networks'
keys in them whatever prefix the training code put in front (`model.`, `module.`, ...)."""
import copyreg
import pickle
import types

from .h5weights import WeightsError, describe_mismatch

COMBINED_FORMAT = "yelan-state-dicts"
# A key every state_dict of the group has; its position in a checkpoint key gives the prefix.
ANCHORS = {"pose": "in_cnn.0.weight", "mask": "inc.double_conv.0.weight"}
# The reference pose net holds its frozen U-Net as submodule `mask_net`.
POSE_HOLDS_MASK = "mask_net."


class _Stub(dict):
    """Stands in for a pickled class that cannot be imported here (pytorch_lightning's
    AttributeDict, torchvision modules kept in hyper-parameters): the tensors are all we
    need. A dict, so that pickled dict items land somewhere; list items go to `_items`."""

    def __new__(cls, *a, **k):
        return dict.__new__(cls)

    def __init__(self, *a, **k):
        pass

    def __setstate__(self, state):
        self.__dict__["_state"] = state

    def append(self, item):
        self.__dict__.setdefault("_items", []).append(item)

    def extend(self, items):
        for item in items:
            self.append(item)


def _reconstructor(cls, base, state):
    if isinstance(cls, type) and issubclass(cls, _Stub):
        obj = base.__new__(base) if base is not object else cls()
        if state is not None and base is dict:
            obj.update(state)
        return obj
    return copyreg._reconstructor(cls, base, state)


class _LenientUnpickler(pickle.Unpickler):
    stubbed = set()

    def find_class(self, module, name):
        if (module, name) == ("copyreg", "_reconstructor"):
            return _reconstructor
        try:
            return super().find_class(module, name)
        except (ImportError, AttributeError):
            _LenientUnpickler.stubbed.add(f"{module}.{name}")
            return type(name, (_Stub,), {"__module__": "stub." + module})


class _LenientPickleModule(types.ModuleType):
    """The pickle module with a lenient Unpickler (every other name from pickle)."""
    Unpickler = _LenientUnpickler

    def __getattr__(self, name):
        return getattr(pickle, name)


lenient_pickle = _LenientPickleModule("lenient_pickle")


def load_checkpoint(path):
    """-> (kind, object): a flat {key: tensor} dict, or our combined dict."""
    import torch
    import torch.serialization as ser
    # torch 1.13's load() ignores its pickle_module argument (it always takes the module
    # global `pickle`), so the lenient one is also put there for the duration of the call.
    saved = ser.pickle
    try:
        ser.pickle = lenient_pickle
        obj = torch.load(path, map_location="cpu", pickle_module=lenient_pickle)
    except FileNotFoundError:
        raise WeightsError(f"{path}: no such file") from None
    except Exception as e:  # torch raises many kinds for a non-checkpoint file
        raise WeightsError(f"{path}: not a PyTorch checkpoint ({type(e).__name__}: {e})") from None
    finally:
        ser.pickle = saved
    if isinstance(obj, dict) and obj.get("format") == COMBINED_FORMAT:
        return "combined", obj
    if isinstance(obj, dict) and isinstance(obj.get("state_dict"), dict):
        obj = obj["state_dict"]  # Lightning
    if isinstance(obj, torch.nn.Module):
        obj = obj.state_dict()
    if not isinstance(obj, dict) or not all(torch.is_tensor(v) for v in obj.values()):
        raise WeightsError(f"{path}: holds neither a state_dict nor a Lightning checkpoint")
    return "flat", obj


def find_prefixes(keys, group):
    anchor = ANCHORS[group]
    return sorted({k[: -len(anchor)] for k in keys if k.endswith(anchor) and
                   (k == anchor or k[-len(anchor) - 1] == ".")})


def extract_group(sd, group, expected, source, prefix=None):
    """The bare state_dict of `group` inside a checkpoint's flat dict (None when absent),
    checked name by name and shape by shape against `expected` {key: shape}."""
    if prefix is None:
        found = find_prefixes(sd.keys(), group)
        if group == "mask" and len(found) > 1:
            # A pose checkpoint and its own U-Net: prefer the U-Net under mask_net.
            held = [p for p in found if p.endswith(POSE_HOLDS_MASK)]
            found = held if len(held) == 1 else found
        if not found:
            return None
        if len(found) > 1:
            raise WeightsError(f"{source}: {group} weights found under several prefixes "
                               f"({', '.join(repr(p) for p in found)}); pass --{group}-prefix")
        prefix = found[0]
    out = {}
    for k, v in sd.items():
        if not k.startswith(prefix):
            continue
        bare = k[len(prefix):]
        if group == "pose" and bare.startswith(POSE_HOLDS_MASK):
            continue
        out[bare] = v
    if not out:
        return None
    problem = describe_mismatch(f"{source} ({group}, prefix {prefix!r})", expected,
                                {k: tuple(v.shape) for k, v in out.items()})
    if problem:
        raise WeightsError(problem)
    return out
