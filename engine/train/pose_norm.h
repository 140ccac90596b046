// The reference code's joint normalisation (SPEC section 6) between camera-frame joints (mm)
// and the network's normalised coordinates, and back:
//   (u, v) = K X;  x_n = (u - W/2) / (W/2);  y_n = (v - H/2) / (H/2);
//   s = z_ref * max(W / fx, H / fy);  R = sqrt(z_ref^2 + s^2);
//   z_n = ((R + z_ref) / s) * (1 - z_ref / Z)
// z_ref is the head's depth: the ground truth under the paper protocol, an estimate in use.
#pragma once
#include <array>

namespace yelan::train {

struct Intrinsics {
  double fx, fy, cx, cy;
  int width, height;
};

std::array<double, 3> normalise_joint(const std::array<double, 3>& cam_mm, const Intrinsics& k, double z_ref);
std::array<double, 3> denormalise_joint(const std::array<double, 3>& norm, const Intrinsics& k, double z_ref);

}  // namespace yelan::train
