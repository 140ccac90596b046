// Arms through their whole range of motion. The 13 training clips hold few of the arm poses of
// their own held-out stretches, and the pose net learns those poses instead of how to read an
// arm from events (models/README.md, sessions 17 and 23). FreeArms drives each arm through key
// poses drawn anywhere in a shoulder's and an elbow's range (hanging, overhead, behind, across
// the chest, straight or folded), hung from the body's own shoulders in its own chest frame,
// so the body, the legs and the head stay the clip's. Keys every 0.3-1.2 s, a monotone cubic
// through them: positions and velocities continuous, speeds a dancer reaches.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "camera/sim/motion.h"

namespace yelan::camera::sim {

// One arm's angles (radians), as the procedural dance's arms are built: the upper arm raised
// by `elevation` from hanging (0) in the chest's frontal plane, swung forward by `plane`
// (negative: behind the body), turned about its own axis by `twist`; the elbow flexes by
// `flex` (0 straight), the hand by flex + `wrist`.
struct ArmAngles {
  double elevation = 0, plane = 0, twist = 0, flex = 0, wrist = 0;
};

// The range the keys are drawn from (degrees). Every angle stays inside it between keys too
// (the curve never overshoots its keys: an elbow never bends backwards).
struct ArmRange {
  double elevation[2] = {0, 175}, plane[2] = {-35, 115}, twist[2] = {-45, 85}, flex[2] = {0, 145}, wrist[2] = {-30, 30};
};

class FreeArms {
 public:
  // Keys for [0, duration_s] (and a second past it), drawn from `seed`; the bone lengths are
  // `shape`'s (body_proportions), as every Motion of that shape has them.
  // Throws std::invalid_argument for seed 0 (the "no free arms" value) or a bad duration.
  FreeArms(const BodyShape& shape, std::uint64_t seed, double duration_s, const ArmRange& range = {});

  // side 0 right, 1 left.
  ArmAngles angles(int side, double t_s) const;
  // `body` with both arms at their angles at t_s: each shoulder stays where `body` has it,
  // elbow, wrist and finger tip follow from the angles in `body`'s chest frame (up: chest to
  // neck; left: the shoulders' line). Every bone keeps its length; nothing else moves.
  BodyPose apply(const BodyPose& body, double t_s) const;

 private:
  BodyProportions prop_;
  ArmRange range_;
  std::vector<double> times_;                   // the keys' times, shared by both arms
  std::array<std::vector<ArmAngles>, 2> keys_;  // right, left
};

}  // namespace yelan::camera::sim
