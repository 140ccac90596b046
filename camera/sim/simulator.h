// The virtual camera: a character performing a motion in a scene, rendered into keyframes at
// an adaptive rate (the next one sooner when the body moved fast in the image: ESIM's rule)
// and turned into events by the pixel model stepping at >= 1 kHz over intensity interpolated
// between keyframes, with exact labels: 3D joints in the camera
// frame at label_hz, the human mask at mask_hz. Results go to a SimSink: a recording file,
// the trainer's stream, previews. Deterministic given the seed, whatever the thread count.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "camera/event.h"
#include "camera/sim/body.h"
#include "camera/sim/characters.h"
#include "camera/sim/dance.h"
#include "camera/sim/free_arms.h"
#include "camera/sim/motion.h"
#include "camera/sim/pixel_model.h"
#include "camera/sim/scene.h"

namespace yelan::camera::sim {

// Everything that decides one simulated recording (a preset or a scene.json gives it).
struct SimSpec {
  std::string name;                 // the preset name, or the config file's stem
  std::string character = "ana";
  std::string motion = "05_04";     // a BVH stem in mocap_dir, or "dance" / "dance<N>" (procedural)
  MotionOptions motion_options;
  // The part of the clip played (fractions of its length after the speed warp), from
  // motion_offset_s into it, back and forth past its ends: datasets draw a start anywhere and
  // hold out a segment of each clip for validation.
  double motion_begin = 0, motion_end = 1;
  double motion_offset_s = 0;
  // Body and clothes varied around the named character (datasets draw them per recording).
  double height_scale = 1, girth_scale = 1;
  std::optional<Clothing> clothing;
  // Nonzero: the character's looks are drawn from this seed (random_looks) and the recording
  // names it looks_name(seed) instead; the scales and clothing above still apply on top.
  std::uint64_t looks_seed = 0;
  // A clip played from anywhere (motion_offset_s, motion_begin) has the dancer wherever the
  // mocap subject had walked to, often out of the picture, facing anywhere. true: the motion
  // is turned so the dancer faces the view's way at the recording's start and shifted so the
  // pelvis's mean floor position over the recording is the scene's centre. Datasets and
  // evaluation scenes set it; presets keep the clip's own placement.
  bool frame_dancer = false;
  // false: nobody in the scene (the room, its moving background, lights and noise alone);
  // labels are all invalid and masks empty. Negative data for stage 1's "nobody there".
  bool dancer = true;
  bool dance_static_legs = false;   // procedural only: upper body moves, legs stay put
  // Nonzero: the right [0] and left [1] arm play the motion this many seconds after the body
  // (inside the segment played, back and forth as the body does), each hung from the body's
  // neck in its chest's frame (with_arm_from): arm and body poses the clip never had
  // together. Datasets draw it for some training recordings (--remix-arms).
  std::array<double, 2> arm_offset_s{0, 0};
  // Nonzero: both arms leave the motion and move through key poses drawn from this seed
  // anywhere in their range (free_arms.h), hung from the body's shoulders: arm poses no clip
  // has. Datasets draw it for some training recordings (--free-arms). Not with arm_offset_s.
  std::uint64_t free_arms_seed = 0;
  // Scale of the character's front cues (Character::front_print): datasets set it for all.
  double front_print = 1;
  SceneConfig scene;
  PixelParams pixel = pixel_params_davis346();
  double duration_s = 2;
  std::uint64_t seed = 1;
  double label_hz = 300;            // 3D joints
  double mask_hz = 50;              // human masks (the training frame rate)
  double max_step_s = 1e-3;         // pixel model steps: at least 1 kHz
  double min_step_s = 5e-5;         // and at most 20 kHz
  double step_lambda = 0.5;         // per pixel step, edges move at most this many pixels and
                                    // flicker changes log intensity by at most this many thresholds
  double max_render_step_s = 4e-3;  // rendered keyframes at least every 4 ms ...
  double render_lambda = 2.0;       // ... and whenever edges may have moved this many pixels
  std::string mocap_dir;            // where BVH stems are looked up (default: ../shared/data/mocap)
};

struct Label {
  std::int64_t t_us;
  Joints13 joints_mm;                      // camera frame
  std::array<std::uint8_t, kJointCount> valid;  // in front of the camera and inside the image
};

class SimSink {
 public:
  virtual ~SimSink() = default;
  virtual void events(std::span<const Event> ev) {}
  virtual void label(const Label& l) {}
  // The rendered sample at a mask tick (intensity, mask after occlusion, depth).
  virtual void mask(std::int64_t t_us, const RenderedFrame& frame) {}
};

struct SimStats {
  std::uint64_t samples = 0, events = 0, labels = 0, masks = 0;  // samples: rendered keyframes
  std::uint64_t pixel_steps = 0;
  double min_step_s = 0, mean_step_s = 0;  // between keyframes
  double render_wall_s = 0, pixel_wall_s = 0;  // time spent rendering and in the pixel model
  PixelStats pixel;
};

class Simulator {
 public:
  explicit Simulator(const SimSpec& spec);
  ~Simulator();
  const SimSpec& spec() const { return spec_; }
  const CameraModel& camera() const { return scene_.camera(); }
  double duration_s() const { return spec_.duration_s; }
  double motion_duration_s() const { return motion_->duration_s(); }
  double time_s() const { return t_; }
  // Runs from the current time to min(t_end_s, duration), feeding the sink.
  void run_until(double t_end_s, SimSink& sink);
  const Character& character() const { return character_; }
  // The scene as JSON (character, clothing, motion, view, lighting, background, seed, ...).
  std::string description_json() const;
  const SimStats& stats() const { return stats_; }
  // Camera-frame labels for a pose (exposed for previews and tests).
  Label label_at(double t_s) const;

 private:
  void sample(double t_s);  // pose -> clothes -> render into frame_ (without flicker)
  // `intensity` (a frame's pixels) under the lamp at t_s: itself, or its copy in lit_ times
  // the flicker factor.
  const float* lit(const float* intensity, double t_s);
  double motion_time(double t_s) const;  // clips longer than their motion play back and forth
  BodyPose pose_at(double t_s) const;    // the motion at t_s, its arms remixed (arm_offset_s) or free
  double image_speed(const BodyPose& a, const BodyPose& b, double dt) const;  // px/s, fastest body point
  BodyPose pose_{}, prev_pose_{};
  SimSpec spec_;
  Character character_;
  std::unique_ptr<Motion> motion_;
  std::unique_ptr<FreeArms> free_arms_;  // null without SimSpec::free_arms_seed
  void frame_motion();
  Dresser dresser_;
  Scene scene_;
  PixelModel pixel_;
  RenderedFrame frame_;
  std::vector<Primitive> prims_;
  std::vector<Event> events_;
  double t_ = 0, pixel_dt_ = 0, render_dt_ = 0;
  std::vector<float> prev_intensity_, interp_, lit_;
  std::int64_t next_label_ = 0, next_mask_ = 0;  // tick indices
  bool started_ = false;
  SimStats stats_;
  double step_sum_ = 0;
};

// The default place of the CMU clips: $YELAN_MOCAP_DIR, else ../shared/data/mocap beside
// the source tree, else the working directory's ../shared/data/mocap.
std::string default_mocap_dir();

// A labelled recording (*.yelan.h5: events, camera, labels, masks, scene attributes) as a
// sink; the file appears, atomically, at close(). Destroyed without close(): no file.
class RecordingWriter final : public SimSink {
 public:
  RecordingWriter(const std::string& path, const Simulator& sim);
  ~RecordingWriter() override;
  void events(std::span<const Event> ev) override;
  void label(const Label& l) override;
  void mask(std::int64_t t_us, const RenderedFrame& frame) override;
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Runs `sim` to its end into `sink` in chunks of simulated time, calling `progress` (may be
// null) after each.
void run_to_end(Simulator& sim, SimSink& sink, void (*progress)(double t_s, double duration_s, void* ctx) = nullptr,
                void* ctx = nullptr);

// A whole recording in one call; returns the stats.
SimStats write_recording(const SimSpec& spec, const std::string& path);

}  // namespace yelan::camera::sim
