// SPEC's 13 joints pair up as the head, then (right, left) from the shoulders to the feet:
// the one pairing the losses, the metrics and the trainer's mirroring all use.
#pragma once

namespace yelan {

// The joint that trades places with joint j when a body's left and right are swapped.
constexpr int mirror_joint(int j) { return j == 0 ? 0 : j % 2 ? j + 1 : j - 1; }

}  // namespace yelan
