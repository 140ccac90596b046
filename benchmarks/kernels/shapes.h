// The convolution shapes of SPEC section 5's networks (paper configuration), named by
// where they occur. Activations are 1 frame (batch 1), as streaming inference runs them.
#pragma once
#include <string>
#include <vector>

namespace yelan::bench {

struct ConvCase {
  std::string where;
  int cin, cout, h, w, k, stride, pad;  // h, w: the input's size
  bool transposed = false;
  int out_pad_h = 0, out_pad_w = 0;
};

inline const std::vector<ConvCase>& network_conv_cases() {
  static const std::vector<ConvCase> cases = {
      // stage 2 backbone (ResNet34 conv1, layer1, layer2)
      {"resnet.conv1", 6, 64, 260, 346, 7, 2, 3},
      {"resnet.layer1", 64, 64, 65, 87, 3, 1, 1},
      {"resnet.layer2.down", 64, 128, 65, 87, 3, 2, 1},
      {"resnet.layer2.shortcut", 64, 128, 65, 87, 1, 2, 0},
      {"resnet.layer2", 128, 128, 33, 44, 3, 1, 1},
      // ConvLSTM gates conv(cat[x, h]) and the fuse / skip blocks
      {"convlstm.gates", 256, 512, 33, 44, 3, 1, 1},
      {"convlstm.fuse", 256, 128, 33, 44, 1, 1, 0},
      {"skip.block", 256, 128, 33, 44, 3, 1, 1},
      // hourglass
      {"hourglass.in", 128, 64, 33, 44, 3, 1, 1},
      {"hourglass.64", 64, 64, 17, 22, 3, 1, 1},
      {"hourglass.128", 128, 128, 17, 22, 3, 1, 1},
      {"hourglass.out", 64, 13, 33, 44, 3, 1, 1},
      {"stage.input", 39, 128, 33, 44, 3, 1, 1},
      // stage 1 U-Net DoubleConvs
      {"unet.inc.a", 6, 64, 260, 346, 3, 1, 1},
      {"unet.inc.b", 64, 64, 260, 346, 3, 1, 1},
      {"unet.down1", 128, 128, 130, 173, 3, 1, 1},
      {"unet.down2", 256, 256, 65, 86, 3, 1, 1},
      {"unet.down3", 512, 512, 32, 43, 3, 1, 1},
      {"unet.down4", 1024, 1024, 16, 21, 3, 1, 1},
      // transposed convolutions: hourglass and residual up blocks, U-Net ups
      {"hourglass.up", 128, 64, 17, 22, 3, 2, 1, true, 0, 1},
      {"hourglass.up.shortcut", 128, 64, 17, 22, 1, 2, 0, true, 0, 1},
      {"unet.up1", 1024, 512, 16, 21, 2, 2, 0, true},
      {"unet.up2", 512, 256, 32, 43, 2, 2, 0, true},
      {"unet.up3", 256, 128, 65, 86, 2, 2, 0, true},
      {"unet.up4", 128, 64, 130, 173, 2, 2, 0, true},
  };
  return cases;
}

}  // namespace yelan::bench
