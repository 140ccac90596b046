// The simulated room around the dancer: the camera (DAVIS346 pinhole, named views or any
// orbit), the lighting levels and flicker, a textured wall and floor, optional dynamic
// background (objects and a person passing along the wall, a waving curtain, a screen) and
// occluders (a box and a pillar, a panel crossing in front). Static parts are rendered once
// and cached; each frame re-renders only what moves.
//
// The dancer stands near the world origin facing -y. View yaw: front = 0 (camera at -y
// looking +y), left = 90 (camera on +x, the dancer's left), back = 180, right = -90.
// Pitch: positive tilts the camera down; kAimAtBody aims it at (0, 0, 1000).
// Everything random is drawn from rng.h keyed by SceneConfig::seed.
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "camera/sim/render.h"
#include "camera/sim/types.h"

namespace yelan::camera::sim {

enum class View { front, back, left, right };
inline constexpr double kAimAtBody = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kBodyAimHeightMm = 1000;

double view_yaw_deg(View v);
const char* view_name(View v);

// A DAVIS346 (346x260) with focal length f px and the principal point at the centre.
CameraModel davis346(double focal_px = kDavis346FocalPx);

// Camera at horizontal distance distance_mm from the z axis, height_mm above the floor,
// turned by yaw about z (front = 0), tilted down by pitch_deg; K from `intrinsics`.
// Throws std::invalid_argument for a non-finite or non-positive distance.
CameraModel orbit_camera(double yaw_deg, double pitch_deg, double distance_mm, double height_mm,
                         const CameraModel& intrinsics);
CameraModel view_camera(View v, double distance_mm = 3500, double height_mm = 1200,
                        double pitch_deg = kAimAtBody, double focal_px = kDavis346FocalPx);
// Camera centre in world coordinates (mm).
Vec3 camera_centre(const CameraModel& cam);

enum class LightLevel { high, medium, low };
const char* light_name(LightLevel l);
const char* camera_motion_name(int motion);  // SceneConfig::CameraMotion: still|pan|shake|sweep
// high ~ office (white facing the light = 255), medium 60, low 20 (a dim lamp: the pixel's
// lin-log knee, where events thin out and noise dominates but a dancer still shows).
// Flicker: 100 Hz ripple of depth 10% (high), 20% (medium), 30% (low).
Lighting lighting(LightLevel level, bool flicker);

struct SceneConfig {
  View view = View::front;
  std::optional<double> yaw_deg;  // when set, replaces the view's yaw
  double pitch_deg = kAimAtBody;
  double distance_mm = 3500;
  double height_mm = 1200;
  CameraModel intrinsics = davis346();  // K and size; M is ignored
  LightLevel light = LightLevel::high;
  // When set, the lamp's level in DN (white facing the light) instead of the lighting's
  // (255 / 60 / 20); ambient share and flicker depth stay the lighting's.
  std::optional<double> light_dn;
  bool flicker = false;
  enum Background { static_wall, dynamic };
  Background background = static_wall;
  bool occluders = false;  // a static box and pillar plus a panel crossing in front
  // The camera's own motion, about its centre: pan sweeps the yaw +-6 deg back and forth
  // every 8 s (a slow pan); shake is a hand-held tremor, about 0.5 deg at 2-7 Hz about every
  // axis (seeded). With a moving camera every frame is rendered whole, and the labels follow
  // the camera; a recording's /camera/M is the camera at rest.
  // sweep: a hand-held camera looking around the room, 2-8 deg of pan and 1-4 of tilt at
  // 0.1-0.5 Hz with a ripple of a quarter of that at 0.6-1.4 Hz: up to tens of deg/s, as a
  // camera held while walking a room (pan turns 6 deg in 2 s, shake trembles by 0.5 deg).
  enum CameraMotion { still, pan, shake, sweep };
  CameraMotion camera_motion = still;
  // A furnished room instead of a bare wall: posters and shelves on the wall, cabinets and
  // tables on the floor, poles and lamps, each seeded (a real room's clutter, which a bare
  // sim room lacks; around the dancer's spot the floor stays clear).
  bool clutter = false;
  std::uint64_t seed = 0;
  RenderOptions render;
};

// A low-light scene's lamp at `dn` DN when dn is set (datasets and evaluations drawn under
// another low light than the simulator's); other scenes are left as they are.
void set_low_light_dn(SceneConfig& scene, std::optional<double> dn);

class Scene {
 public:
  explicit Scene(const SceneConfig& config);

  const CameraModel& camera() const { return renderer_.camera(); }  // at rest
  CameraModel camera_at(double t_s) const;                           // with its motion
  // An upper bound of how fast the camera's motion moves the image, px/s (0 when still).
  double camera_image_speed() const;
  const Lighting& light() const { return light_; }
  const SceneConfig& config() const { return config_; }

  // Renders the dancer's primitives (those flagged human make the mask) in the scene at t;
  // without the lamp's flicker when `flicker` is false (its factor is light().flicker(t)).
  void render(double t_s, const std::vector<Primitive>& human, RenderedFrame& out, bool flicker = true);

  // What the scene adds: fixed primitives, and the moving ones at time t.
  const std::vector<Primitive>& static_primitives() const { return static_; }
  void dynamic_primitives(double t_s, std::vector<Primitive>& out) const;

  std::string description() const;

 private:
  struct Mover {  // a rigid group of primitives sliding along the wall and wrapping around
    std::vector<Primitive> parts;
    double speed_mm_s = 0, phase_mm = 0, span_mm = 0;
    bool walker = false;  // legs and arms swing
  };

  SceneConfig config_;
  Lighting light_;
  Renderer renderer_;
  // A moving camera's frames, each rendered whole: one renderer kept, so its buffers are
  // not allocated and faulted in anew on every frame.
  Renderer moving_;
  Vec3 ahead_, right_;  // horizontal unit vectors: camera towards the body, image right
  double wall_mm_ = 0;
  std::vector<Primitive> static_;
  std::vector<Mover> movers_;
  std::vector<Primitive> curtain_;
  std::vector<double> curtain_phase_;
  std::optional<Primitive> screen_, panel_;
  double panel_speed_ = 0, panel_phase_ = 0, panel_span_ = 0;
  std::vector<Primitive> frame_prims_;
  // Camera motion: per axis (x tilt, y pan, z roll) two sinusoids, amplitude (rad), rate
  // (rad/s) and phase.
  struct Wobble {
    double amp = 0, rate = 0, phase = 0;
  };
  std::array<std::array<Wobble, 2>, 3> wobble_{};
};

}  // namespace yelan::camera::sim
