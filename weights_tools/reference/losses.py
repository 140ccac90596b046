"""The training losses, as the reference code computes them (SPEC 6; see engine/losses.h).

HPE per stage: masked mean over (frame, joint) of |joints - target| + JS(xy, G(x, y)) +
JS(zy, G(z, y)) + JS(xz, G(x, z)), with G a Gaussian of sigma 1 heatmap pixel normalised
to sum 1 and KL(p, q) = sum p (log(p + 1e-24) - log(q + 1e-24)); stages averaged.
Mask: BCE(logits[:, :1], labels[:, :1]) + BCE(logits, labels) + MSE(scores, 1 - mean |sigmoid
(logits) - labels| over pixels, detached).
"""
import torch
import torch.nn.functional as F

from .dsnt import joints_from_heatmaps, pixel_centres

EPS = 1e-24


def gaussian(mu, h, w, sigma_px=1.0):
    """mu (..., 2) = (width coordinate, height coordinate) -> (..., h, w) maps summing to 1."""
    xs = pixel_centres(w, mu.device, mu.dtype)
    ys = pixel_centres(h, mu.device, mu.dtype)
    sx, sy = 2 * sigma_px / w, 2 * sigma_px / h
    gx = torch.exp(-0.5 * ((xs - mu[..., 0:1]) / sx) ** 2)  # (..., w)
    gy = torch.exp(-0.5 * ((ys - mu[..., 1:2]) / sy) ** 2)  # (..., h)
    g = gy.unsqueeze(-1) * gx.unsqueeze(-2)
    return g / (g.sum(dim=(-2, -1), keepdim=True) + EPS)


def kl(p, q):
    return (p * ((p + EPS).log() - (q + EPS).log())).sum(dim=(-2, -1))


def js(p, q):
    m = 0.5 * (p + q)
    return 0.5 * kl(p, m) + 0.5 * kl(q, m)


def masked_mean(losses, valid):
    return (losses * valid).sum() / valid.sum().clamp(min=1)


def hpe_loss(heatmaps, target, valid):
    """heatmaps: list over stages of (xy, zy, xz[, depth]) maps (N, J, h, w); target (N, J, 3);
    valid (N, J) float. -> (loss, [per-stage losses])."""
    per_stage = []
    for maps in heatmaps:
        xy, zy, xz = maps[:3]
        h, w = xy.shape[-2:]
        joints = joints_from_heatmaps(*maps)
        e = torch.linalg.norm(joints - target, dim=-1)
        x, y, z = target[..., 0:1], target[..., 1:2], target[..., 2:3]
        e = e + js(xy, gaussian(torch.cat([x, y], -1), h, w))
        e = e + js(zy, gaussian(torch.cat([z, y], -1), h, w))
        e = e + js(xz, gaussian(torch.cat([x, z], -1), h, w))
        per_stage.append(masked_mean(e, valid))
    return sum(per_stage) / len(per_stage), per_stage


def mask_loss(logits, scores, labels):
    """-> (loss, bce_first, bce_all, score_mse)."""
    first = F.binary_cross_entropy_with_logits(logits[:, 0:1], labels[:, 0:1])
    full = F.binary_cross_entropy_with_logits(logits, labels)
    target = 1 - (torch.sigmoid(logits).detach() - labels).abs().mean(dim=(2, 3))
    mse = F.mse_loss(scores, target)
    return first + full + mse, first, full, mse
