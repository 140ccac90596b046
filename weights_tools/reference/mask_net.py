"""Stage 1: U-Net giving N mask logits (current + N-1 future) and a confidence score each."""
import torch
from torch import nn
import torch.nn.functional as F


class DoubleConv(nn.Module):
    def __init__(self, cin, cout):
        super().__init__()
        self.double_conv = nn.Sequential(
            nn.Conv2d(cin, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout),
            nn.ReLU(inplace=True),
            nn.Conv2d(cout, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout),
            nn.ReLU(inplace=True))

    def forward(self, x):
        return self.double_conv(x)


class Down(nn.Module):
    def __init__(self, cin, cout):
        super().__init__()
        self.maxpool_conv = nn.Sequential(nn.MaxPool2d(2), DoubleConv(cin, cout))

    def forward(self, x):
        return self.maxpool_conv(x)


class Up(nn.Module):
    """ConvTranspose 2x2/2 halving the channels, zero-pad to the skip's size (the odd pixel
    goes right/bottom), cat[skip, upsampled], DoubleConv."""

    def __init__(self, cin, cout):
        super().__init__()
        self.up = nn.ConvTranspose2d(cin, cin // 2, 2, stride=2)
        self.conv = DoubleConv(cin, cout)  # cat of skip (cin//2) and upsampled (cin//2)

    def forward(self, x, skip):
        x = self.up(x)
        dy = skip.shape[2] - x.shape[2]
        dx = skip.shape[3] - x.shape[3]
        x = F.pad(x, [dx // 2, dx - dx // 2, dy // 2, dy - dy // 2])
        return self.conv(torch.cat([skip, x], dim=1))


class OutConv(nn.Module):
    def __init__(self, cin, cout):
        super().__init__()
        self.conv = nn.Conv2d(cin, cout, 1)

    def forward(self, x):
        return self.conv(x)


class MaskNet(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        w = cfg.unet_widths()
        if any(w[k + 1] != 2 * w[k] for k in range(4)):
            # Up halves the channels of the deeper map so that it matches the skip.
            raise ValueError(f"U-Net widths {w} do not double level to level; "
                             "choose a width multiplier with 64*mult an integer")
        self.inc = DoubleConv(cfg.channels, w[0])
        self.down1 = Down(w[0], w[1])
        self.down2 = Down(w[1], w[2])
        self.down3 = Down(w[2], w[3])
        self.down4 = Down(w[3], w[4])
        self.up1 = Up(w[4], w[3])
        self.up2 = Up(w[3], w[2])
        self.up3 = Up(w[2], w[1])
        self.up4 = Up(w[1], w[0])
        hid = w[0]
        self.outc = OutConv(hid, cfg.n_masks)
        # No activation between the two 1x1 convs (as the reference).
        self.score_conv = nn.Sequential(nn.Conv2d(hid, hid * 4, 1), nn.Conv2d(hid * 4, hid * 8, 1))
        self.avgpool = nn.AdaptiveAvgPool2d((1, 1))
        self.fc = nn.Linear(hid * 8, cfg.n_masks)
        self.pool = cfg.mask_pool

    def forward(self, x):
        """x (N, C, H, W) -> mask logits (N, n_masks, H, W), scores in (0,1) (N, n_masks)."""
        size = x.shape[2:]
        if self.pool > 1:
            x = F.avg_pool2d(x, self.pool)
        x1 = self.inc(x)
        x2 = self.down1(x1)
        x3 = self.down2(x2)
        x4 = self.down3(x3)
        x5 = self.down4(x4)
        y = self.up1(x5, x4)
        y = self.up2(y, x3)
        y = self.up3(y, x2)
        y = self.up4(y, x1)
        masks = self.outc(y)
        if self.pool > 1:
            masks = F.interpolate(masks, size=size, mode="bilinear", align_corners=False)
        s = torch.flatten(self.avgpool(self.score_conv(y)), 1)
        return masks, torch.sigmoid(self.fc(s))
