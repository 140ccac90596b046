#include "camera/sim/presets.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace yelan::camera::sim {

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string part;
  std::istringstream in(s);
  while (std::getline(in, part, sep)) out.push_back(part);
  return out;
}

bool parse_view(const std::string& s, View& v) {
  for (View c : {View::front, View::back, View::left, View::right})
    if (s == view_name(c)) return v = c, true;
  return false;
}
bool parse_light(const std::string& s, LightLevel& l) {
  for (LightLevel c : {LightLevel::high, LightLevel::medium, LightLevel::low})
    if (s == light_name(c)) return l = c, true;
  return false;
}
bool parse_background(const std::string& s, SceneConfig::Background& b) {
  if (s == "static") return b = SceneConfig::static_wall, true;
  if (s == "dynamic") return b = SceneConfig::dynamic, true;
  return false;
}

// A camera motion by its name (camera_motion_name's inverse).
bool parse_camera_motion(const std::string& s, SceneConfig::CameraMotion& m) {
  for (const auto c : {SceneConfig::still, SceneConfig::pan, SceneConfig::shake, SceneConfig::sweep})
    if (s == camera_motion_name(c)) return m = c, true;
  return false;
}

[[noreturn]] void bad_preset(const std::string& name, const std::string& why) {
  throw std::invalid_argument("preset '" + name + "': " + why +
                              " (expected <character>-<motion>-<view>-<light>-<bg> or <view>-<light>-<bg>, "
                              "view front|back|left|right, light high|medium|low, bg static|dynamic, "
                              "optionally ending in -occluded, -flicker, -clutter, -pan, -shake or -sweep and/or -empty)");
}

}  // namespace

const std::vector<std::string>& train_motions() {
  static const std::vector<std::string> m = {"05_04", "05_07", "05_14", "05_19", "02_01", "02_03", "05_03",
                                             "05_05", "05_11", "05_13", "05_15", "05_18", "05_20"};
  return m;
}
const std::vector<std::string>& test_motions() {
  static const std::vector<std::string> m = {"05_16", "93_03", "05_17", "05_09", "05_10"};
  return m;
}

SimSpec preset_spec(const std::string& name) {
  std::vector<std::string> parts = split(name, '-');
  SimSpec spec;
  spec.name = name;
  // A still camera has no suffix: "still" is not one.
  SceneConfig::CameraMotion motion = SceneConfig::still;
  while (!parts.empty() && (parts.back() == "occluded" || parts.back() == "flicker" || parts.back() == "empty" ||
                            parts.back() == "clutter" ||
                            (parse_camera_motion(parts.back(), motion) && motion != SceneConfig::still))) {
    if (parts.back() == "empty") spec.dancer = false;
    else if (parts.back() == "clutter") spec.scene.clutter = true;
    else if (parts.back() == "occluded" || parts.back() == "flicker")
      (parts.back() == "occluded" ? spec.scene.occluders : spec.scene.flicker) = true;
    else spec.scene.camera_motion = motion;
    parts.pop_back();
  }
  if (parts.size() != 3 && parts.size() != 5) bad_preset(name, "wrong number of fields");
  const std::size_t k = parts.size() - 3;
  if (k == 2) {
    spec.character = parts[0];
    spec.motion = parts[1];
    character_by_name(spec.character);  // a clear error now rather than deep in the run
  }
  if (!parse_view(parts[k], spec.scene.view)) bad_preset(name, "unknown view '" + parts[k] + "'");
  if (!parse_light(parts[k + 1], spec.scene.light)) bad_preset(name, "unknown lighting '" + parts[k + 1] + "'");
  if (!parse_background(parts[k + 2], spec.scene.background))
    bad_preset(name, "unknown background '" + parts[k + 2] + "'");
  return spec;
}

SimSpec spec_from_json(const std::string& text, const std::string& what) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(what + ": not JSON: " + e.what());
  }
  if (!j.is_object()) throw std::invalid_argument(what + ": expected a JSON object");
  SimSpec s = j.contains("preset") ? preset_spec(j.at("preset").get<std::string>()) : SimSpec{};
  static const std::vector<std::string> known = {
      "preset", "name", "character", "motion", "speed", "mirror", "yaw_offset_deg", "static_legs", "view", "yaw_deg",
      "pitch_deg", "distance_mm", "height_mm", "focal_px", "lighting", "light_dn", "flicker", "background", "occluders", "clutter", "camera_motion",
      "duration_s", "seed", "label_hz", "mask_hz", "max_step_s", "min_step_s", "step_lambda", "max_render_step_s", "render_lambda", "pixel", "mocap_dir", "looks_seed", "arm_offset_s", "free_arms_seed", "front_print"};
  for (auto& [key, value] : j.items())
    if (std::find(known.begin(), known.end(), key) == known.end())
      throw std::invalid_argument(what + ": unknown key '" + key + "'");
  try {
    auto str = [&](const char* k, std::string& out) {
      if (j.contains(k)) out = j.at(k).get<std::string>();
    };
    auto num = [&](const nlohmann::json& o, const char* k, double& out) {
      if (o.contains(k)) out = o.at(k).get<double>();
    };
    str("name", s.name);
    str("character", s.character);
    str("motion", s.motion);
    str("mocap_dir", s.mocap_dir);
    num(j, "speed", s.motion_options.speed);
    num(j, "yaw_offset_deg", s.motion_options.yaw_deg);
    if (j.contains("mirror")) s.motion_options.mirror = j.at("mirror").get<bool>();
    if (j.contains("static_legs")) s.dance_static_legs = j.at("static_legs").get<bool>();
    if (j.contains("arm_offset_s")) {
      const auto o = j.at("arm_offset_s").get<std::vector<double>>();
      if (o.size() != 2) throw std::invalid_argument("arm_offset_s must be [right, left] (two numbers)");
      s.arm_offset_s = {o[0], o[1]};
    }
    std::string v;
    if (j.contains("view") && !parse_view(v = j.at("view").get<std::string>(), s.scene.view))
      throw std::invalid_argument("view '" + v + "' is not front|back|left|right");
    if (j.contains("yaw_deg")) s.scene.yaw_deg = j.at("yaw_deg").get<double>();
    num(j, "pitch_deg", s.scene.pitch_deg);
    num(j, "distance_mm", s.scene.distance_mm);
    num(j, "height_mm", s.scene.height_mm);
    if (j.contains("focal_px")) s.scene.intrinsics = davis346(j.at("focal_px").get<double>());
    if (j.contains("lighting") && !parse_light(v = j.at("lighting").get<std::string>(), s.scene.light))
      throw std::invalid_argument("lighting '" + v + "' is not high|medium|low");
    if (j.contains("light_dn")) s.scene.light_dn = j.at("light_dn").get<double>();
    if (j.contains("flicker")) s.scene.flicker = j.at("flicker").get<bool>();
    if (j.contains("background") && !parse_background(v = j.at("background").get<std::string>(), s.scene.background))
      throw std::invalid_argument("background '" + v + "' is not static|dynamic");
    if (j.contains("occluders")) s.scene.occluders = j.at("occluders").get<bool>();
    if (j.contains("clutter")) s.scene.clutter = j.at("clutter").get<bool>();
    if (j.contains("camera_motion") && !parse_camera_motion(v = j.at("camera_motion").get<std::string>(), s.scene.camera_motion))
      throw std::invalid_argument("camera_motion '" + v + "' is not still|pan|shake|sweep");
    // One line per JSON key, as SPEC names them: a table of fields, deliberately spelled out.
    num(j, "duration_s", s.duration_s);
    if (j.contains("seed")) s.seed = j.at("seed").get<std::uint64_t>();
    if (j.contains("looks_seed")) s.looks_seed = j.at("looks_seed").get<std::uint64_t>();
    if (j.contains("free_arms_seed")) s.free_arms_seed = j.at("free_arms_seed").get<std::uint64_t>();
    num(j, "front_print", s.front_print);
    num(j, "label_hz", s.label_hz);
    num(j, "mask_hz", s.mask_hz);
    num(j, "max_step_s", s.max_step_s);
    num(j, "min_step_s", s.min_step_s);
    num(j, "step_lambda", s.step_lambda);
    num(j, "max_render_step_s", s.max_render_step_s);
    num(j, "render_lambda", s.render_lambda);
    if (j.contains("pixel")) {
      const auto& p = j.at("pixel");
      PixelParams& q = s.pixel;
      num(p, "pos_threshold", q.pos_threshold);
      num(p, "neg_threshold", q.neg_threshold);
      num(p, "sigma_threshold", q.sigma_threshold);
      num(p, "cutoff_hz", q.cutoff_hz);
      num(p, "refractory_s", q.refractory_s);
      num(p, "leak_rate_hz", q.leak_rate_hz);
      num(p, "shot_noise_rate_hz", q.shot_noise_rate_hz);
      num(p, "hot_pixel_fraction", q.hot_pixel_fraction);
      num(p, "hot_pixel_rate_hz", q.hot_pixel_rate_hz);
      num(p, "lin_log_knee", q.lin_log_knee);
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(what + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(what + ": " + e.what());
  }
  if (s.motion.empty()) throw std::invalid_argument(what + ": empty motion");
  character_by_name(s.character);
  return s;
}

std::vector<std::string> grid_presets(const std::string& which, const GridFilter& f) {
  if (which != "train" && which != "test" && which != "all")
    throw std::invalid_argument("grid '" + which + "': expected train, test or all");
  auto keep = [](const std::vector<std::string>& filter, const std::string& v) {
    return filter.empty() || std::find(filter.begin(), filter.end(), v) != filter.end();
  };
  std::vector<std::string> out;
  for (const Character& c : characters()) {
    const bool test = c.test_only;
    if ((which == "train" && test) || (which == "test" && !test) || !keep(f.characters, c.name)) continue;
    std::vector<std::string> motions = test ? test_motions() : train_motions();
    motions.push_back("dance");
    for (const std::string& m : motions) {
      if (!keep(f.motions, m)) continue;
      for (const char* v : {"front", "back", "left", "right"})
        for (const char* l : {"high", "medium", "low"})
          for (const char* b : {"static", "dynamic"})
            if (keep(f.views, v) && keep(f.lights, l) && keep(f.backgrounds, b))
              // Held-out characters are also tested behind occluders; training sees occlusion
              // only as augmentation.
              for (const char* o : {"", "-occluded"})
                if (test || !*o) out.push_back(c.name + "-" + m + "-" + v + "-" + l + "-" + b + o);
    }
  }
  return out;
}

}  // namespace yelan::camera::sim
