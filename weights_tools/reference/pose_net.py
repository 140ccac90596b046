"""Stage 2: ResNet34 head -> ConvLSTM over the window -> fuse/skip -> stacked hourglasses
giving xy/zy/xz marginal heatmaps per stage, and DSNT joints from the last stage."""
import torch
from torch import nn

from .blocks import down_block, flat_softmax, regular_block, resnet_layer, up_block
from .dsnt import joints_from_heatmaps


def head_output_size(h, w, head_stride=8):
    """Spatial size after conv1 (7x7/2 p3), maxpool (3x3/2 p1) and layer2's stride (2, or 1
    at head_stride 4)."""
    for k, s, p in ((7, 2, 3), (3, 2, 1), (3, head_stride // 4, 1)):
        h = (h + 2 * p - k) // s + 1
        w = (w + 2 * p - k) // s + 1
    return h, w


class ConvLSTMCell(nn.Module):
    """gates = conv3x3(cat[x, h]) split i, f, o, g; c' = f c + i g; h' = o tanh(c')."""

    def __init__(self, cin, hidden):
        super().__init__()
        self.hidden = hidden
        self.conv = nn.Conv2d(cin + hidden, 4 * hidden, 3, padding=1, bias=True)

    def forward(self, x, h, c):
        i, f, o, g = torch.split(self.conv(torch.cat([x, h], dim=1)), self.hidden, dim=1)
        c = torch.sigmoid(f) * c + torch.sigmoid(i) * torch.tanh(g)
        h = torch.sigmoid(o) * torch.tanh(c)
        return h, c


class WindowConvLSTM(nn.Module):
    """One layer. bidirectional: the same cell runs forward and backward over the window
    from zero state, outputs per frame cat[h_fwd, h_bwd] -> 1x1 fuse conv (2h -> h).
    causal: forward only, fuse conv h -> h."""

    def __init__(self, cin, hidden, bidirectional):
        super().__init__()
        self.bidirectional = bidirectional
        self.cell_list = nn.ModuleList([ConvLSTMCell(cin, hidden)])
        fuse_in = 2 * hidden if bidirectional else hidden
        self.fuse_list = nn.ModuleList([nn.Conv2d(fuse_in, hidden, 1, bias=True)])

    def _run(self, frames):
        cell = self.cell_list[0]
        b, _, hh, ww = frames[0].shape
        h = frames[0].new_zeros(b, cell.hidden, hh, ww)
        c = torch.zeros_like(h)
        out = []
        for x in frames:
            h, c = cell(x, h, c)
            out.append(h)
        return out

    def forward(self, x):
        """x (B, S, C, H, W) -> (B, S, hidden, H, W)."""
        b, s = x.shape[:2]
        frames = [x[:, t] for t in range(s)]
        fwd = self._run(frames)
        if self.bidirectional:
            bwd = self._run(frames[::-1])[::-1]
            per_frame = [torch.cat([f, r], dim=1) for f, r in zip(fwd, bwd)]
        else:
            per_frame = fwd
        y = torch.stack(per_frame, dim=1)
        y = self.fuse_list[0](y.reshape(b * s, *y.shape[2:]))
        return y.reshape(b, s, *y.shape[1:])


class HourglassStage(nn.Module):
    def __init__(self, cin, joints, lo, hi, mid_hw, skip=False):
        super().__init__()
        self.skip = skip  # pose.hourglass_skip: up block's output + the second down block's
        # Output padding so that 2x up-sampling restores the mid size exactly.
        op = (int(mid_hw[0] % 2 == 0), int(mid_hw[1] % 2 == 0))
        self.down_layers = nn.Sequential(
            regular_block(cin, lo), regular_block(lo, lo), down_block(lo, hi),
            regular_block(hi, hi), regular_block(hi, hi))
        self.up_layers = nn.Sequential(
            regular_block(hi, hi), regular_block(hi, hi), up_block(hi, lo, op),
            regular_block(lo, lo), regular_block(lo, joints))

    def forward(self, x):
        if not self.skip:
            return self.up_layers(self.down_layers(x))
        early = self.down_layers[1](self.down_layers[0](x))
        y = self.up_layers[2](self.up_layers[1](self.up_layers[0](self.down_layers[4](self.down_layers[3](
            self.down_layers[2](early))))))
        return self.up_layers[4](self.up_layers[3](y + early))


class HeatmapCombiner(nn.Module):
    def __init__(self, joints, out_ch):
        super().__init__()
        self.combine_block = regular_block(3 * joints, out_ch)

    def forward(self, x):
        return self.combine_block(x)


class PoseNet(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        self.cfg = cfg
        c64, mid = cfg.resnet_widths()
        self.in_cnn = nn.Sequential(
            nn.Conv2d(2 * cfg.channels if cfg.outside_input else cfg.channels, c64, 7, stride=2, padding=3, bias=False),
            nn.BatchNorm2d(c64), nn.ReLU(inplace=True),
            nn.MaxPool2d(3, stride=2, padding=1),
            resnet_layer(c64, c64, 3, 1),
            resnet_layer(c64, mid, 4, cfg.head_stride // 4))
        self.mid_hw = head_output_size(cfg.height, cfg.width, cfg.head_stride)
        if cfg.convlstm != "none":
            self.cl = WindowConvLSTM(mid, cfg.hidden, cfg.convlstm == "bidirectional")
        self.cl_skip_block = regular_block(mid + (cfg.hidden if cfg.convlstm != "none" else 0), mid)
        lo, hi = cfg.hourglass_widths()
        self.xy_hm_cnns = nn.ModuleList()
        self.zy_hm_cnns = nn.ModuleList()
        self.xz_hm_cnns = nn.ModuleList()
        self.hm_combiners = nn.ModuleList()
        for t in range(cfg.stages):
            if t > 0:
                self.hm_combiners.append(HeatmapCombiner(cfg.joints, mid))
            for plane in (self.xy_hm_cnns, self.zy_hm_cnns, self.xz_hm_cnns):
                plane.append(HourglassStage(mid, cfg.joints, lo, hi, self.mid_hw, cfg.hourglass_skip))
        if cfg.depth_map:  # pose.depth_map: one more hourglass per stage, its output depth maps
            self.depth_hm_cnns = nn.ModuleList(
                HourglassStage(mid, cfg.joints, lo, hi, self.mid_hw, cfg.hourglass_skip)
                for _ in range(cfg.stages))

    def forward(self, x):
        """x (S, C, H, W) or (B, S, C, H, W): one or B windows.
        Returns (heatmaps, joints): heatmaps[t] = (xy, zy, xz), each (B*S, J, h, w)
        probability maps of stage t, followed by its depth maps with pose.depth_map; joints
        (B*S, J, 3) normalised, from the last stage."""
        if x.dim() == 4:
            x = x.unsqueeze(0)
        b, s = x.shape[:2]
        feats = self.in_cnn(x.reshape(b * s, *x.shape[2:]))
        if self.cfg.convlstm != "none":
            cl = self.cl(feats.reshape(b, s, *feats.shape[1:]))
            feats = torch.cat([feats, cl.reshape(b * s, *cl.shape[2:])], dim=1)
        feats = self.cl_skip_block(feats)
        heatmaps = []
        inp = feats
        for t in range(self.cfg.stages):
            if t > 0:
                # Cumulative, as the reference: stage t sees feats + sum of combiners 1..t.
                inp = inp + self.hm_combiners[t - 1](torch.cat(heatmaps[t - 1][:3], dim=1))
            maps = tuple(flat_softmax(plane[t](inp))
                         for plane in (self.xy_hm_cnns, self.zy_hm_cnns, self.xz_hm_cnns))
            if self.cfg.depth_map:
                maps = maps + (self.depth_hm_cnns[t](inp),)
            heatmaps.append(maps)
        return heatmaps, joints_from_heatmaps(*heatmaps[-1])
