#include "engine/model_config.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#ifndef YELAN_SOURCE_DIR
#define YELAN_SOURCE_DIR "."
#endif

namespace yelan {
namespace {

using nlohmann::json;

const json& section(const json& d, const char* key, const std::string& where) {
  if (!d.contains(key) || !d[key].is_object()) throw ConfigError(where + ": missing object '" + key + "'");
  return d[key];
}

int get_int(const json& o, const std::string& path, const char* key) {
  if (!o.contains(key)) throw ConfigError(path + ": missing key '" + key + "'");
  const json& v = o[key];
  if (!v.is_number_integer()) throw ConfigError(path + "." + key + ": expected an integer, got " + v.dump());
  return v.get<int>();
}

double get_num(const json& o, const std::string& path, const char* key) {
  if (!o.contains(key)) throw ConfigError(path + ": missing key '" + key + "'");
  const json& v = o[key];
  if (!v.is_number()) throw ConfigError(path + "." + key + ": expected a number, got " + v.dump());
  return v.get<double>();
}

std::string get_str(const json& o, const std::string& path, const char* key) {
  if (!o.contains(key)) throw ConfigError(path + ": missing key '" + key + "'");
  if (!o[key].is_string()) throw ConfigError(path + "." + key + ": expected a string, got " + o[key].dump());
  return o[key].get<std::string>();
}

bool get_bool_or(const json& o, const std::string& path, const char* key, bool fallback) {
  if (!o.contains(key)) return fallback;
  if (!o[key].is_boolean()) throw ConfigError(path + "." + key + ": expected true or false, got " + o[key].dump());
  return o[key].get<bool>();
}

}  // namespace

int ModelConfig::scaled(int base, double mult) {
  return std::max(1, int(std::nearbyint(base * mult)));  // Python's round(): half to even
}

ModelConfig parse_model_config(const std::string& text, const std::string& where) {
  json d;
  try {
    d = json::parse(text);
  } catch (const json::parse_error& e) {
    throw ConfigError(where + ": not valid JSON: " + e.what());
  }
  if (!d.is_object()) throw ConfigError(where + ": expected a JSON object");
  const json& i = section(d, "input", where);
  const json& m = section(d, "mask", where);
  const json& p = section(d, "pose", where);
  ModelConfig c;
  c.json = text;
  c.name = get_str(d, where, "name");
  c.channels = get_int(i, where + ".input", "channels");
  c.sensor_height = get_int(i, where + ".input", "sensor_height");
  c.sensor_width = get_int(i, where + ".input", "sensor_width");
  c.downscale = get_int(i, where + ".input", "downscale");
  c.window = get_int(i, where + ".input", "window");
  c.mask_width = get_num(m, where + ".mask", "width_mult");
  c.n_masks = get_int(m, where + ".mask", "n_masks");
  c.mask_pool = m.contains("pool") ? get_int(m, where + ".mask", "pool") : 1;
  c.mask_crop_margin = m.contains("crop_margin") ? get_int(m, where + ".mask", "crop_margin") : 0;
  c.pose_width = get_num(p, where + ".pose", "width_mult");
  c.hidden = get_int(p, where + ".pose", "hidden");
  c.stages = get_int(p, where + ".pose", "stages");
  c.joints = get_int(p, where + ".pose", "joints");
  const std::string mode = get_str(p, where + ".pose", "convlstm");
  if (mode != "bidirectional" && mode != "causal" && mode != "none")
    throw ConfigError(where + ": pose.convlstm must be bidirectional, causal or none, got '" + mode + "'");
  c.bidirectional = mode == "bidirectional";
  c.convlstm = mode != "none";
  c.masked_input = get_bool_or(p, where + ".pose", "masked_input", true);
  c.mask_role = m.contains("role") ? get_str(m, where + ".mask", "role") : c.masked_input ? "mask" : "none";
  c.outside_input = get_bool_or(p, where + ".pose", "outside_input", false);
  c.crop_margin = p.contains("crop_margin") ? get_int(p, where + ".pose", "crop_margin") : 0;
  c.head_stride = p.contains("head_stride") ? get_int(p, where + ".pose", "head_stride") : 8;
  c.hourglass_skip = get_bool_or(p, where + ".pose", "hourglass_skip", false);
  c.depth_map = get_bool_or(p, where + ".pose", "depth_map", false);
  c.representation = i.contains("representation") ? get_str(i, where + ".input", "representation") : "tore";
  if (d.contains("run")) {
    const json& r = section(d, "run", where);
    if (r.contains("beta")) c.run_beta = get_num(r, where + ".run", "beta");
    if (r.contains("depth_scale")) c.depth_scale = get_num(r, where + ".run", "depth_scale");
    c.depth_forearms = get_bool_or(r, where + ".run", "depth_forearms", true);
    if (r.contains("mask_mirror") && r["mask_mirror"].is_number()) c.mask_mirror_doubt = get_num(r, where + ".run", "mask_mirror");
    else c.mask_mirror = get_bool_or(r, where + ".run", "mask_mirror", false);
    c.run_bf16 = get_bool_or(r, where + ".run", "bf16", false);
    c.run_pose_bf16 = get_bool_or(r, where + ".run", "pose_bf16", false);
    if (r.contains("mask_max_age_bf16")) c.mask_max_age_bf16 = get_int(r, where + ".run", "mask_max_age_bf16");
    if (r.contains("mask_max_age_bf16_winograd"))
      c.mask_max_age_bf16_winograd = get_int(r, where + ".run", "mask_max_age_bf16_winograd");
    if (r.contains("depth_tau_s")) c.depth_tau_s = get_num(r, where + ".run", "depth_tau_s");
    if (r.contains("pose_tau_s")) c.pose_tau_s = get_num(r, where + ".run", "pose_tau_s");
    if (r.contains("mask_cut")) c.mask_cut = get_num(r, where + ".run", "mask_cut");
    if (r.contains("mask_cut_reused")) c.mask_cut_reused = get_num(r, where + ".run", "mask_cut_reused");
    if (r.contains("idle_recheck_s")) c.idle_recheck_s = get_num(r, where + ".run", "idle_recheck_s");
    if (r.contains("mask_grow")) c.mask_grow = get_int(r, where + ".run", "mask_grow");
    if (r.contains("mask_max_age")) c.mask_max_age = get_int(r, where + ".run", "mask_max_age");
    if (r.contains("presence")) {
      const json& pr = section(r, "presence", where + ".run");
      c.presence_a = get_num(pr, where + ".run.presence", "a");
      c.presence_b = get_num(pr, where + ".run.presence", "b");
      if (pr.contains("tau_s")) c.presence_tau_s = get_num(pr, where + ".run.presence", "tau_s");
      c.presence_calibrated = true;
    }
  }
  const struct { bool ok; const char* msg; } checks[] = {
      {c.channels >= 1, "input.channels must be >= 1"},
      {c.downscale >= 1, "input.downscale must be >= 1"},
      {c.window >= 1, "input.window must be >= 1"},
      {c.crop_margin >= 0, "pose.crop_margin must be >= 0"},
      {c.mask_crop_margin >= 0 && c.mask_crop_margin <= 4096, "mask.crop_margin must lie in 0..4096 (input pixels; 0: the whole frame)"},
      {c.head_stride == 8 || c.head_stride == 4, "pose.head_stride must be 8 or 4"},
      {c.presence_tau_s >= 0 && c.presence_tau_s <= 60, "run.presence.tau_s must lie in 0..60 (seconds)"},
      {c.depth_tau_s >= 0 && c.depth_tau_s <= 60, "run.depth_tau_s must lie in 0..60 (seconds)"},
      {c.pose_tau_s >= 0 && c.pose_tau_s <= 10, "run.pose_tau_s must lie in 0..10 (seconds)"},
      {c.idle_recheck_s >= 0 && c.idle_recheck_s <= 1, "run.idle_recheck_s must lie in 0..1 (seconds)"},
      {ModelConfig::mask_mirror_doubt_ok(c.mask_mirror_doubt),
       "run.mask_mirror must be true, false or a P(person) margin d in (0, 0.5)"},
      {c.mask_grow >= 0 && c.mask_grow <= 64, "run.mask_grow must lie in 0..64 (input pixels)"},
      {c.mask_max_age >= 0 && c.mask_max_age <= 1000, "run.mask_max_age must lie in 0..1000 (frames of 20 ms; 0: none)"},
      {c.mask_max_age_bf16.value_or(0) >= 0 && c.mask_max_age_bf16.value_or(0) <= 1000,
       "run.mask_max_age_bf16 must lie in 0..1000 (frames of 20 ms; 0: none)"},
      {c.mask_max_age_bf16_winograd.value_or(0) >= 0 && c.mask_max_age_bf16_winograd.value_or(0) <= 1000,
       "run.mask_max_age_bf16_winograd must lie in 0..1000 (frames of 20 ms; 0: none)"},
      {c.mask_role == "mask" || c.mask_role == "presence" || c.mask_role == "none",
       "mask.role must be mask, presence or none"},
      {(c.mask_role == "mask") == c.masked_input,
       "mask.role mask goes with pose.masked_input true, presence and none with false"},
      {!c.outside_input || c.masked_input, "pose.outside_input needs pose.masked_input (a mask to be outside of)"},
      {!c.outside_input || 2 * c.channels <= 16, "pose.outside_input needs input.channels <= 8 (one channel block)"},
      {c.mask_width > 0 && c.pose_width > 0, "width_mult must be > 0"},
      {c.n_masks >= 1 && c.hidden >= 1 && c.stages >= 1 && c.joints >= 1,
       "n_masks, hidden, stages and joints must be >= 1"},
      {c.representation == "tore" || c.representation == "counts", "input.representation must be tore or counts"},
      {c.representation != "tore" || c.channels % 2 == 0, "input.channels must be even for TORE (2K planes)"},
      {c.representation != "counts" || c.channels == 2, "input.channels must be 2 for counts (one per polarity)"},
      {c.run_beta >= 0 && c.run_beta <= 2, "run.beta must be in 0..2 (above 1: stage 1 on every tick)"},
      {c.depth_scale > 0 && c.depth_scale <= 1000, "run.depth_scale must be in (0, 1000]"},
      {c.mask_cut > 0 && c.mask_cut < 1, "run.mask_cut must be in (0, 1)"},
      {c.reused_mask_cut() > 0 && c.reused_mask_cut() < 1, "run.mask_cut_reused must be in (0, 1)"},
      {std::isfinite(c.presence_a) && std::isfinite(c.presence_b) && c.presence_a >= 0,
       "run.presence: a must be finite and >= 0, b finite"},
      {c.downscale >= 1 && c.height() >= 16 && c.width() >= 16, "input is smaller than 16 x 16 after downscale"},
      {c.mask_pool >= 1 && c.mask_pool <= 8, "mask.pool must be in 1..8"},
      {c.mask_pool >= 1 && c.height() / c.mask_pool >= 16 && c.width() / c.mask_pool >= 16,
       "stage 1's input is smaller than 16 x 16 after mask.pool"},
  };
  for (const auto& ch : checks)
    if (!ch.ok) throw ConfigError(where + ": " + ch.msg);
  return c;
}

std::string with_run_setting(const std::string& text, const std::string& key, const std::string& value_json) {
  nlohmann::ordered_json d, v;
  try {
    d = nlohmann::ordered_json::parse(text);
    v = nlohmann::ordered_json::parse(value_json);
  } catch (const json::parse_error& e) {
    throw ConfigError(std::string("config: not valid JSON: ") + e.what());
  }
  if (!d.is_object()) throw ConfigError("config: expected a JSON object");
  if (d.contains("run") && !d["run"].is_object()) throw ConfigError("config: 'run' is not an object");
  d["run"][key] = v;
  std::string out = d.dump() + "\n";
  parse_model_config(out, "config with run." + key);
  return out;
}

ModelConfig load_model_config(const std::string& name_or_path) {
  std::string path = name_or_path;
  if (!std::filesystem::exists(path)) path = std::string(YELAN_SOURCE_DIR) + "/weights_tools/configs/" + name_or_path + ".json";
  std::ifstream f(path);
  if (!f) throw ConfigError("no config '" + name_or_path + "' (not a file, not in weights_tools/configs/)");
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_model_config(ss.str(), path);
}

}  // namespace yelan
