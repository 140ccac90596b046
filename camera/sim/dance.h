// Procedural dance: unlimited seeded variety on the same skeleton (and bone lengths) as the
// retargeted BVH clips. A phrase of moves on the beat (arm waves and raises, steps, squats,
// kicks, hip sway, grooves, turns, spins, jumps with a ballistic root), cross-faded so
// positions and velocities are continuous at any t; legs by two-bone IK with the feet on the
// floor and the knees bending forward, elbows flexing one way only.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "camera/sim/motion.h"

namespace yelan::camera::sim {

struct DanceParams {
  double tempo_bpm = 120;   // 40..240
  double energy = 0.7;      // 0..1: amplitude of every move
  double arm_style = 0.5;   // 0..1: 0 flowing waves, 1 sharp raises and punches
  double leg_style = 0.5;   // 0..1: 0 grounded (steps, sway), 1 bouncy (squats, kicks)
  double jump_prob = 0.1;   // 0..1: share of moves that are jumps
  double spin_prob = 0.1;   // 0..1: share of moves that are 360 deg spins
  double turn_prob = 0.1;   // 0..1: share of moves that are quarter or half turns
  bool static_legs = false; // upper body only: pelvis, legs and feet never move (the
                            // "missing torso" / static limbs case)
};

// Seeded draw of all the above (static_legs one time in ten).
DanceParams random_dance_params(std::uint64_t seed);

enum class DanceMoveKind : std::uint8_t { groove, arm_wave, arm_raise, torso, step_touch, hip_sway,
                                          squat, kick, turn, spin, jump };
const char* dance_move_name(DanceMoveKind k);

// One move of the phrase. Turns and spins rotate the facing by yaw_change_rad between
// event_t0_s and event_t1_s; a jump is airborne between event_t0_s and event_t1_s.
struct DanceMove {
  DanceMoveKind kind;
  double t0_s, t1_s;
  double event_t0_s = 0, event_t1_s = 0, yaw_change_rad = 0;
};

class ProceduralDance : public Motion {
 public:
  virtual const std::vector<DanceMove>& moves() const = 0;
};

// Throws std::invalid_argument for parameters out of range or duration <= 0.
std::unique_ptr<ProceduralDance> make_procedural_dance(const DanceParams& params, const BodyShape& shape,
                                                       std::uint64_t seed, double duration_s);

}  // namespace yelan::camera::sim
