// Motion: a body pose at any time. BVH clips are retargeted onto our character (each bone
// keeps its direction from the clip and takes its length from the character's proportions),
// so any BodyShape can perform any clip; dance.h makes procedural ones on the same skeleton.
// World: mm, z up, floor z = 0, rest facing -y (types.h).
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "camera/sim/bvh.h"
#include "camera/sim/types.h"

namespace yelan::camera::sim {

class Motion {
 public:
  virtual ~Motion();
  virtual double duration_s() const = 0;
  // Pose at t (seconds), clamped to [0, duration]; cheap (a few microseconds), thread-safe.
  virtual BodyPose at(double t_s) const = 0;
  virtual std::string name() const = 0;
};

struct MotionOptions {
  double speed = 1.0;            // time warp, 0.5..2: the clip plays `speed` times faster
  bool mirror = false;           // reflect x (after re-centring) and swap left/right
  bool recentre = true;          // pelvis over the world origin at t = 0, facing -y
  double yaw_deg = 0;            // then turn the whole motion about the world z axis
  bool skip_first_frame = true;  // CMU's conversion puts a synthetic T-pose in frame 1
};

// Segment lengths of our skeleton (mm), from standing height and sex. See motion.cpp for the
// ratios (Drillis-Contini via Winter) and where they are adjusted.
struct BodyProportions {
  double pelvis_chest, chest_neck, neck_head;        // spine; neck_head = neck base -> skull centre
  double head_top, head_nose, head_chin;             // skull centre -> top / nose / chin
  double half_shoulder, upper_arm, forearm, hand;    // neck -> shoulder, ..., wrist -> finger tip
  double half_hip, thigh, shank, foot;               // pelvis -> hip joint, ..., ankle -> toe tip
  double ankle_height;                               // ankle above the floor, foot flat
  double hip_height;                                 // pelvis above the floor, standing
  // Head points in the head frame (u = up, f = forward), relative to the skull centre.
  double nose_up, chin_fwd, chin_up, nose_fwd;
};
BodyProportions body_proportions(const BodyShape& shape);

// The rigid bones of the skeleton: |p[a] - p[b]| == length_mm in every pose any Motion makes.
struct Bone {
  BodyPoint a, b;
  double length_mm;
};
std::vector<Bone> body_bones(const BodyShape& shape);

// Left/right swap of every pair and x -> -x (a reflection in the plane x = 0).
BodyPose mirror_pose(const BodyPose& pose);

// `body` with the arm on `side` (0 right, 1 left: shoulder, elbow, wrist, finger tip) taken
// from `arms`: each of its points relative to arms' neck, turned from arms' chest frame into
// body's (up: chest -> neck; across: the shoulders' line) and hung from body's neck. Every
// bone keeps its length; the rest of body is unchanged. A pose the clip never had, from two
// that it had (SimSpec::arm_offset_s).
BodyPose with_arm_from(const BodyPose& body, const BodyPose& arms, int side);

// The turn about the world z axis that makes `pose` face -y (the rest facing and the views'
// front), its facing taken from the hips: (left - right) x up.
Eigen::Matrix3d turn_to_face_minus_y(const BodyPose& pose);

// BVH axes (Y up, rest facing +Z) to ours (z up, rest facing -y): (X, Y, Z) -> (X, -Z, Y),
// a proper rotation. BVH left (+X) stays our +x, which is a -y-facing character's left.
inline Vec3 bvh_axes_to_world(const Eigen::Vector3d& v) { return Vec3(v.x(), -v.z(), v.y()); }

// Which BVH joints drive which body points. Index 0 = right, 1 = left. Recognises CMU
// MotionBuilder names (LeftUpLeg, LeftArm, ...), CMU ASF names (lfemur, lhumerus, ...) and
// Mixamo names ("mixamorig:LeftArm"; any "prefix:" is ignored), case-insensitively.
struct BvhBodyMap {
  int hip[2], knee[2], ankle[2], toe_tip[2];     // toe_tip: the toe joint's End Site, or the toe joint
  int shoulder[2], elbow[2], wrist[2];
  int chest, neck, head, head_top;               // chest: a spine joint (see motion.cpp); head_top may be -1
  int toe[2];                                    // the toe joint itself (-1 when the foot's End Site is used)
};
// Throws BvhError listing every body part it could not find (with the names it tried).
BvhBodyMap map_bvh_body(const BvhClip& clip);

// The stated source of each DHP19 joint (kDhp19Points order): BVH joint name and how.
struct Dhp19Source {
  BodyPoint point;
  std::string bvh_joint;
  std::string how;
};
std::array<Dhp19Source, kJointCount> dhp19_bvh_sources(const BvhClip& clip);

std::unique_ptr<Motion> load_bvh_motion(const std::string& path, const BodyShape& shape,
                                        const MotionOptions& opt = {});
std::unique_ptr<Motion> make_bvh_motion(BvhClip clip, const BodyShape& shape, const MotionOptions& opt = {});

}  // namespace yelan::camera::sim
