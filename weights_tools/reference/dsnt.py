"""DSNT soft-argmax and the 3D joint read-out from three marginal heatmaps."""
import torch


def pixel_centres(n, device=None, dtype=torch.float32):
    """Normalised pixel-centre coordinates: linspace(-(n-1)/n, (n-1)/n, n)."""
    return torch.linspace(-(n - 1) / n, (n - 1) / n, n, device=device, dtype=dtype)


def dsnt(heatmaps):
    """(N, J, H, W) probability maps -> (N, J, 2) expectations, (width coord, height coord)."""
    _, _, h, w = heatmaps.shape
    xs = pixel_centres(w, heatmaps.device, heatmaps.dtype)
    ys = pixel_centres(h, heatmaps.device, heatmaps.dtype)
    x = (heatmaps.sum(dim=2) * xs).sum(dim=-1)
    y = (heatmaps.sum(dim=3) * ys).sum(dim=-1)
    return torch.stack([x, y], dim=-1)


def joints_from_heatmaps(xy, zy, xz, depth=None):
    """Normalised 3D joints (N, J, 3): x, y from xy; z = mean of zy's width coordinate and
    xz's height coordinate, or with depth maps (pose.depth_map) their mean under xy."""
    pxy = dsnt(xy)
    if depth is not None:
        z = (xy * depth).sum(dim=(-2, -1)).unsqueeze(-1)
    else:
        pzy, pxz = dsnt(zy), dsnt(xz)
        z = 0.5 * (pzy[..., 0:1] + pxz[..., 1:2])
    return torch.cat([pxy, z], dim=-1)
