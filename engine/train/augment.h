// Geometric augmentation of a training window: one random similarity (scale, in-plane
// rotation, shift) applied to every frame's input and to the joints, as if the camera had
// rolled, panned and the dancer stood nearer or farther. The joints stay a 3D pose whose
// projection is the warped picture: image points move with the warp, and the body moves
// along the optical axis so that its head's depth is z_ref / scale. And a mirror image of
// the window, left to right: cells trade places, nothing is resampled, so the input keeps
// the statistics the camera gives (a warp's bilinear resampling smooths them).
#pragma once
#include <array>

#include "camera/sim/rng.h"
#include "camera/sim/window_stream.h"
#include "engine/train/pose_norm.h"
#include "layers/param.h"

namespace yelan::train {

struct Similarity {
  double scale = 1, angle_rad = 0, shift_x = 0, shift_y = 0;  // shifts in sensor pixels
};

// scale log-uniform in [0.8, 1.25], angle within +-15 deg, shifts within +-10% of the frame.
Similarity draw_similarity(camera::sim::Rng& r, int sensor_w, int sensor_h);

// The zoom and shift that frame the dancer: the box around every valid joint's projection
// over frames [first, first + count) of the window, grown by `grow` of its size on each side,
// centred and scaled to fill the frame (scale at most `most`, and not below 1: a dancer
// bigger than the frame is only centred). No valid joint: the identity. What a stage 2 reading
// a crop of the dancer would see (the "oracle crop" of the stick diagnostic, --frame-zoom).
Similarity framing_similarity(const camera::sim::SimWindow& w, int first, int count, double grow = 0.1, double most = 4);

// Sensor point (u, v) under the warp, about the frame's centre.
std::array<double, 2> warp_point(const Similarity& s, double u, double v, int sensor_w, int sensor_h);

// Frame n of `a` (an input at 1/d of the sensor) resampled bilinearly under the warp, every
// channel; what falls outside the frame reads 0 (no events).
void warp_frame(const layers::Act& a, int n, const Similarity& s, int d, int sensor_w, int sensor_h);

// A camera-frame joint (mm) under the warp, and the head depth that goes with it
// (z_ref / scale): its projection is warp_point of the joint's, its depth offset from the
// head unchanged.
std::array<double, 3> warp_joint(const Similarity& s, const std::array<double, 3>& p, const Intrinsics& k, double z_ref);

// A camera-frame joint under layers::flip_frame's mirror of a picture `cells_w` cells of d pixels
// wide: its image point u goes to cells_w * d - u (pixel i spans [i, i + 1), as in
// warp_point), v and the depth kept. Left and right trade names too; the caller swaps them.
std::array<double, 3> flip_joint(const std::array<double, 3>& p, const Intrinsics& k, int cells_w, int d);

}  // namespace yelan::train
