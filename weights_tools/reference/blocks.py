"""Building blocks. Attribute names (and Sequential indices) are part of the state_dict
contract: `module.0` is a conv, `module.1` its BN, and so on (see README.md)."""
import torch
from torch import nn


class ResidualBlock(nn.Module):
    """MargiPose residual block: conv-BN-ReLU-conv3x3-BN-ReLU, plus shortcut conv-BN, summed
    (no ReLU after the sum). The first conv and the shortcut conv set stride/transposition."""

    def __init__(self, out_ch, first_conv, shortcut_conv):
        super().__init__()
        self.module = nn.Sequential(
            first_conv, nn.BatchNorm2d(out_ch), nn.ReLU(inplace=True),
            nn.Conv2d(out_ch, out_ch, 3, padding=1, bias=False), nn.BatchNorm2d(out_ch),
            nn.ReLU(inplace=True))
        self.shortcut = nn.Sequential(shortcut_conv, nn.BatchNorm2d(out_ch))

    def forward(self, x):
        return self.module(x) + self.shortcut(x)


def regular_block(cin, cout):
    return ResidualBlock(cout, nn.Conv2d(cin, cout, 3, padding=1, bias=False),
                         nn.Conv2d(cin, cout, 1, bias=False))


def down_block(cin, cout):
    return ResidualBlock(cout, nn.Conv2d(cin, cout, 3, stride=2, padding=1, bias=False),
                         nn.Conv2d(cin, cout, 1, stride=2, bias=False))


def up_block(cin, cout, output_padding):
    return ResidualBlock(
        cout,
        nn.ConvTranspose2d(cin, cout, 3, stride=2, padding=1, output_padding=output_padding,
                           bias=False),
        nn.ConvTranspose2d(cin, cout, 1, stride=2, output_padding=output_padding, bias=False))


class BasicBlock(nn.Module):
    """torchvision's ResNet BasicBlock (same attribute names): ReLU after the sum."""

    def __init__(self, cin, cout, stride=1):
        super().__init__()
        self.conv1 = nn.Conv2d(cin, cout, 3, stride=stride, padding=1, bias=False)
        self.bn1 = nn.BatchNorm2d(cout)
        self.relu = nn.ReLU(inplace=True)
        self.conv2 = nn.Conv2d(cout, cout, 3, padding=1, bias=False)
        self.bn2 = nn.BatchNorm2d(cout)
        self.downsample = None
        if stride != 1 or cin != cout:
            self.downsample = nn.Sequential(nn.Conv2d(cin, cout, 1, stride=stride, bias=False),
                                            nn.BatchNorm2d(cout))

    def forward(self, x):
        identity = x if self.downsample is None else self.downsample(x)
        y = self.relu(self.bn1(self.conv1(x)))
        y = self.bn2(self.conv2(y))
        return self.relu(y + identity)


def resnet_layer(cin, cout, blocks, stride):
    layers = [BasicBlock(cin, cout, stride)]
    layers += [BasicBlock(cout, cout) for _ in range(blocks - 1)]
    return nn.Sequential(*layers)


def flat_softmax(x):
    """Softmax over all H*W positions of each (sample, channel) map."""
    n, c, h, w = x.shape
    return torch.softmax(x.reshape(n, c, h * w), dim=-1).reshape(n, c, h, w)
