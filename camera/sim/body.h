// Turns a BodyPose into render primitives: flesh (ellipsoids and round cones sized from the
// character's height, girth and sex), clothing printed on it, and loose cloth and hair that
// follow the body through damped springs, so a skirt swings after the hips and flares out
// in a spin. Every primitive has human = true and a pattern frame that moves with the part
// it is printed on (torso stripes turn with the torso), so texture edges make events.
// Stripes vary along a frame's u axis (render.cpp): u runs along the part (hoops around the
// trunk, limbs, skirt) unless the character has stripes_along.
//
// Primitive order (stable, tests rely on it): head, jaw, neck, chest, belly, flank R/L,
// pelvis, shoulder R/L, upper arm/forearm/hand R then L, thigh/shin/foot R then L (22), then
// hair cap, 3 hair cones, hat crown and brim, and the cloth's cone shell, each if present.
//
// Loose cloth (cone shell from the hips, or from mid-trunk for a loose shirt, to the hem):
// the hem's centre and radius chase a target that hangs mostly under gravity, flares in a
// spin (tan(angle) = w^2 r / g for the hips' yaw rate w, at most 1 rad for a skirt or
// dress, 0.5 for a coat, 0.35 for a shirt) and is pushed open and along by the legs.
// Springs (stiffness k in 1/s^2, damping ratio z; critically damped is z = 1):
//   skirt, dress and coat hem centre and hem radius  k =  60, z = 0.80  (settles in ~0.7 s)
//   loose shirt hem                                   k = 150, z = 0.70
//   long hair (3 segments)                            k = 120, z = 0.50
// each scaled by a factor in [0.9, 1.1] drawn from the seed. Damping acts on the velocity
// relative to the attachment (capped at 4 m/s), so cloth carried at a steady speed does not
// trail and a teleported pose still swings over smoothly. Integration is semi-implicit
// Euler in substeps of at most 1 ms with the spring targets interpolated across the step,
// so any update interval from 0.1 ms to 20 ms is stable. A step over 0.25 s or backwards
// in time restarts the cloth at rest.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "camera/sim/characters.h"
#include "camera/sim/types.h"

namespace yelan::camera::sim {

class Dresser {
 public:
  // Upper bound on what primitives() appends (body 22, hair 4, hat 2, cloth 1).
  static constexpr int kMaxPrimitives = 31;

  // Throws std::invalid_argument when the shape is absurd (height outside 500..3000 mm,
  // girth outside 0.3..3, or not finite).
  Dresser(const Character& character, std::uint64_t seed);

  // Moves the body to `pose` (world mm) and advances the cloth and hair to time t_s
  // (seconds). The first call sets them at rest. Allocates nothing. Throws
  // std::invalid_argument (state unchanged) when a point or t_s is not finite.
  void update(const BodyPose& pose, double t_s);

  // Appends the current primitives (all human = true) to `out`; reserve kMaxPrimitives to
  // keep this allocation-free. Call after update().
  void primitives(std::vector<Primitive>& out) const;

  // The swinging cloth's hem (skirt, dress, coat or loose shirt), for tests and previews.
  bool has_hem() const { return hem_.active; }
  Vec3 hem_centre() const { return hem_.x; }
  double hem_radius() const { return hem_.r; }
  // Where the hem would hang at rest for the current pose.
  Vec3 hem_rest_centre() const { return hem_.target; }
  bool has_long_hair() const { return hair_active_; }
  Vec3 hair_tip() const { return hair_x_[kHairNodes - 1]; }

  const Character& character() const { return character_; }

 private:
  static constexpr int kHairNodes = 4;  // the anchor on the head and three free nodes

  // Flesh sizes in mm from height, girth and sex (see body.cpp for the proportions).
  struct Dims {
    double head_side, head_depth, jaw_r, neck_r;
    double chest_lat_per_shoulder, chest_depth, belly_lat, belly_depth;
    double pelvis_lat_extra, pelvis_depth, pelvis_up;
    double upper_arm_r0, upper_arm_r1, forearm_r0, forearm_r1, hand_r0, hand_r1;
    double thigh_r0, thigh_r1, shin_r0, shin_r1, foot_r0, foot_r1;
  };

  // Body-fixed axes of the shoulders, hips and head: lat points to the character's left,
  // fwd to where it faces, up along the spine (or to the top of the skull).
  struct Axes {
    Vec3 lat = Vec3::UnitX(), fwd = -Vec3::UnitY(), up = Vec3::UnitZ();
  };
  struct Hem {
    bool active = false;
    double top_offset = 0;  // attachment: pelvis + up_hip * top_offset
    double ra = 0;          // radius at the attachment
    double length = 0;      // slant length from attachment to hem at rest
    double rest_angle = 0;  // half-angle of the cone at rest, rad
    double max_angle = 0;   // fully flared: 1 rad for skirts, less for a coat or shirt
    double k = 0, c = 0;    // stiffness 1/s^2, damping 1/s
    Vec3 x = Vec3::Zero(), v = Vec3::Zero(), target = Vec3::Zero();
    double r = 0, vr = 0, r_target = 0;
  };

  void compute_axes();
  void hem_targets(Vec3& centre, double& radius, double yaw_rate) const;
  Vec3 hair_anchor() const;
  Vec3 hair_direction() const;
  void reset_at_rest();

  Character character_;
  std::uint64_t seed_;
  Dims dims_{};
  bool started_ = false;
  double t_ = 0;
  BodyPose pose_{};
  Axes torso_, hips_, head_;
  double head_up_ = 100;  // head centre to top of skull, mm
  double yaw_rate_ = 0;   // of the hips about z, rad/s (drives the flare)

  Hem hem_;
  bool hair_active_ = false;
  double hair_k_ = 0, hair_c_ = 0, hair_segment_ = 0;
  std::array<Vec3, kHairNodes> hair_x_{}, hair_v_{};
  std::array<std::uint32_t, kMaxPrimitives> print_seeds_{};
};

}  // namespace yelan::camera::sim
