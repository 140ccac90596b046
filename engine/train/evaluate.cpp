#include "engine/train/evaluate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <optional>
#include <functional>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"
#include "camera/sim/rng.h"
#include "camera/sim/window_stream.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "engine/input.h"
#include "engine/train/batch.h"
#include "engine/train/mask_overlap.h"
#include "engine/train/mask_picture.h"
#include "camera/repr/preview_png.h"
#include "weights_tools/network_io.h"
#include "weights_tools/weights_file.h"

namespace yelan::train {

namespace sim = camera::sim;

std::vector<std::string> draw_test_scenes(std::uint64_t seed, int count) {
  const auto all = sim::grid_presets("test");
  // Group by condition (view, light, background and occlusion: the fields after character
  // and motion), then take conditions in turn.
  std::map<std::string, std::vector<std::string>> by_cond;
  for (const auto& n : all) by_cond[n.substr(n.find('-', n.find('-') + 1) + 1)].push_back(n);
  std::vector<const std::vector<std::string>*> conds;
  for (const auto& [c, v] : by_cond) conds.push_back(&v);
  std::vector<std::string> out;
  for (int k = 0; k < count; ++k) {
    // A stride coprime with the 48 conditions: consecutive scenes differ in view, light and
    // background, and any 48 in a row cover every condition once.
    const auto& members = *conds[std::size_t(k) * 7 % conds.size()];
    out.push_back(members[sim::hash64(seed, 0xe7a1, std::uint64_t(k)) % members.size()]);
  }
  return out;
}

void place_in_clip(sim::SimSpec& s, std::uint64_t seed, std::size_t i, bool framed) {
  s.frame_dancer = framed;
  if (s.motion.rfind("dance", 0) != 0) s.motion_offset_s = 30 * sim::uniform01(seed, 0x0ff5e7, i);
}

EvalResult evaluate(const EvalSpec& spec, std::ostream& err) {
  weights::LoadedNetworks nets(weights::load_weights(spec.weights), spec.weights);
  if (spec.mask_grow) nets.cfg.mask_grow = *spec.mask_grow;
  const ModelConfig& cfg = nets.cfg;
  MaskNet& mask = nets.mask;
  PoseNet& pose = nets.pose;
  layers::NoGrad no_grad;

  EvalResult res;
  res.config = cfg.name;
  PoseMetrics all, oracle;
  std::map<std::string, std::map<std::string, PoseMetrics>> cond;
  MaskOverlap overlap;
  std::map<std::string, std::map<std::string, MaskOverlap>> cond_iou;
  BatchBuilder builder(cfg, 1, spec.true_mask ? MaskSource::truth : MaskSource::net);
  std::optional<Floors> floors;
  if (spec.floors) floors.emplace(training_floor_stats(240, 25, spec.framed));
  SwapShare swaps;
  std::set<std::string> picture_names;
  ErrorSplit split, split_floor;
  // One window's buffers serve every window (its frames' TORE read-outs are 2 MB each).
  sim::SimWindow win;
  // One scene or recording: `windows` windows from `next`, scored under `conditions`.
  auto score = [&](int windows, const std::function<void(sim::SimWindow&)>& next,
                   const std::map<std::string, std::string>& conditions, const std::string& scene_name) {
    for (int k = 0; k < windows; ++k) {
      next(win);
      builder.clear();
      const Similarity zoom = framing_similarity(win, 0, cfg.window);
      builder.add(win, mask, nullptr, spec.frame_zoom ? &zoom : nullptr);
      const Batch& b = builder.batch();
      pose.forward(b.input.act, cfg.window);
      const std::vector<float>& jn = pose.joints();
      for (int t = 0; t < cfg.window; ++t) {
        const Pose13 pred = predicted_pose_mm(b, jn, t);
        const auto valid = valid_joints(b, t);
        all.add(pred, b.truth_mm[std::size_t(t)], valid);
        for (const auto& [name, value] : conditions) cond[name][value].add(pred, b.truth_mm[std::size_t(t)], valid);
        const auto view = conditions.find("view");
        const std::string view_name = view != conditions.end() ? view->second : "";
        const Pose13& truth = b.truth_mm[std::size_t(t)];
        split.add(pred, truth, valid, b.k);
        if (floors) {
          floors->add(truth, valid, b.k, b.z_ref[std::size_t(t)], view_name);
          split_floor.add(floors->per_view_prediction(truth, view_name), truth, valid, b.k);
        }
        swaps.add(pred, b.truth_mm[std::size_t(t)], valid, view_name.empty() ? "unknown" : view_name);
        if (spec.keep_poses)
          res.poses.push_back({scene_name, view_name, /*window=*/k, /*frame=*/t, win.frames[std::size_t(t)].t_us,
                               b.z_ref[std::size_t(t)], b.k, pred, truth, valid});
        const Pose13 swapped = swap_left_right(pred);
        const auto frame_error = [&](const Pose13& q) {
          double e = 0;
          for (int j = 0; j < kJoints; ++j)
            if (valid[std::size_t(j)]) {
              const auto& a = q[std::size_t(j)];
              const auto& c = b.truth_mm[std::size_t(t)][std::size_t(j)];
              e += std::sqrt((a[0] - c[0]) * (a[0] - c[0]) + (a[1] - c[1]) * (a[1] - c[1]) + (a[2] - c[2]) * (a[2] - c[2]));
            }
          return e;
        };
        oracle.add(frame_error(swapped) < frame_error(pred) ? swapped : pred, b.truth_mm[std::size_t(t)], valid);
      }
      // Stage 1 IoU: the current mask (binarised at the model's run.mask_cut) against the true
      // mask, at the net's size.
      if (builder.source() == MaskSource::net) {
        const layers::Act& m = mask.masks();
        const int d = cfg.downscale;
        std::vector<float> keep;
        const MaskOverlap before = overlap;
        for (int t = 0; t < cfg.window; ++t) {
          const auto& truth = win.frames[std::size_t(t)].mask;
          input::mask_cut(m, t, 0, keep, float(cfg.mask_cut));
          const auto& frame = win.frames[std::size_t(t)];
          if (!spec.mask_pictures.empty() && k == windows / 2 && t == cfg.window - 1 && !frame.tore.empty()) {
            const int sh = win.camera.height, sw = win.camera.width;
            // A scene drawn twice (--sim test with more than 48 scenes) gets its index too.
            std::string file = scene_name;
            if (!picture_names.insert(file).second) file += "-" + std::to_string(picture_names.size());
            picture_names.insert(file);
            camera::write_png_rgb(spec.mask_pictures + "/" + file + ".png", sw, sh,
                                  mask_picture_rgb(frame.tore.data(), int(frame.tore.size() / (2 * std::size_t(sh) * std::size_t(sw))),
                                                   sh, sw, truth.data(), keep.data(), m.h, m.w, d));
            ++res.mask_pictures;
          }
          add_mask_overlap(overlap, truth.data(), win.camera.width, keep.data(), m.h, m.w, d);
        }
        for (const auto& [name, value] : conditions) cond_iou[name][value] += overlap - before;
      }
    }
  };
  sim::WindowStreamOptions o;
  o.window = cfg.window;
  o.counts = cfg.representation == "counts";
  o.warmup_s = 0.1;
  o.history_s = spec.history_s;
  const int max_windows = std::max(1, int(std::floor(spec.seconds_per_scene * o.frame_hz / cfg.window)));
  const std::size_t total = spec.scenes.size() + spec.recordings.size();
  for (std::size_t i = 0; i < spec.scenes.size(); ++i) {
    sim::SimSpec s = spec.scenes[i];
    sim::WindowStreamOptions so = o;
    // Anywhere in the clip, after history_s of events (a procedural dance has no clip end).
    place_in_clip(s, spec.seed, i, spec.framed);
    so.warmup_s = std::max(o.warmup_s, spec.history_s);
    so.scene_s = so.warmup_s + max_windows * cfg.window / o.frame_hz + 1e-6;
    sim::SimWindowStream stream({s}, sim::hash64(spec.seed, 0xe7a1, i), so);
    const sim::Character& ch = sim::character_by_name(s.character);
    score(max_windows, [&](sim::SimWindow& w) { stream.next(w); },
          {{"lighting", sim::light_name(s.scene.light)},
           {"background", s.scene.background == sim::SceneConfig::dynamic ? "dynamic" : "static"},
           {"view", sim::view_name(s.scene.view)},
           {"character", s.character},
           {"clothing", sim::clothing_name(ch.clothing)},
           {"occlusion", s.scene.occluders ? "occluded" : "clear"},
           {"scene", s.name}},
          s.name);
    err << "[" << (i + 1) << "/" << total << "] " << s.name << ": MPJPE so far " << std::fixed << std::setprecision(1)
        << all.scores().mpjpe_mm << " mm\n";
  }
  for (std::size_t i = 0; i < spec.recordings.size(); ++i) {
    sim::RecordingWindowStream stream({spec.recordings[i]}, spec.seed, o);
    const sim::RecordingInfo& r = stream.info(0);
    const int windows = std::min(max_windows, stream.windows_in(0));
    std::map<std::string, std::string> conditions = {{"lighting", r.lighting}, {"background", r.background},
                                                     {"view", r.view},         {"character", r.character},
                                                     {"occlusion", r.occluded ? "occluded" : "clear"},
                                                     {"scene", r.name},
                                                     {"people", r.dancer ? "dancer" : "nobody"}};
    try {
      conditions["clothing"] = sim::clothing_name(sim::character_by_name(r.character).clothing);
    } catch (const std::exception&) {
      // a character this build does not know: no clothing group
    }
    for (auto it = conditions.begin(); it != conditions.end();) it = it->second.empty() ? conditions.erase(it) : std::next(it);
    if (windows == 0) err << r.path << ": too short for one window of " << cfg.window << " frames; skipped\n";
    score(windows, [&](sim::SimWindow& w) { stream.next(w); }, conditions, r.name);
    err << "[" << (spec.scenes.size() + i + 1) << "/" << total << "] " << r.name << ": MPJPE so far " << std::fixed
        << std::setprecision(1) << all.scores().mpjpe_mm << " mm\n";
  }
  res.all = all.scores();
  res.swap_oracle = oracle.scores();
  const bool no_stage1 = spec.true_mask || !cfg.masked_input;
  res.mask_iou = no_stage1 ? -1 : overlap.iou();
  res.mask_iou_off_edge = no_stage1 ? -1 : overlap.iou_off_edge();
  res.mask_iou_px = no_stage1 ? -1 : overlap.iou_px();
  for (const auto& [name, values] : cond)
    for (const auto& [value, m] : values)
      if (m.scores().frames > 0) res.by_condition[name][value] = m.scores();  // empty scenes score no frame
  for (const auto& [name, values] : cond_iou)
    for (const auto& [value, iu] : values) {
      if (iu.uni > 0) res.mask_iou_by_condition[name][value] = iu.iou();
      if (iu.uni_off_edge > 0) res.mask_iou_off_edge_by_condition[name][value] = iu.iou_off_edge();
      if (iu.uni_px > 0) res.mask_iou_px_by_condition[name][value] = iu.iou_px();
    }
  res.scenes = total;
  res.split = split.scores();
  if (floors) {
    res.floors = floors->scores();
    res.split_per_view_floor = split_floor.scores();
  }
  res.swap_share_by_view = swaps.by_view();
  return res;
}

namespace {
nlohmann::ordered_json scores_json(const PoseScores& s) {
  if (s.frames == 0)  // nothing scored (an empty scene, or no pose said person): n/a, not 0 mm
    return {{"mpjpe_mm", nullptr}, {"pck150", nullptr}, {"auc", nullptr}, {"mpjpe_root_mm", nullptr},
            {"pck150_root", nullptr}, {"auc_root", nullptr}, {"frames", 0}};
  return {{"mpjpe_mm", s.mpjpe_mm}, {"pck150", s.pck150}, {"auc", s.auc}, {"mpjpe_root_mm", s.mpjpe_root_mm},
          {"pck150_root", s.pck150_root}, {"auc_root", s.auc_root}, {"frames", s.frames}};
}
using camera::sim::kJointNames;

// image_px, depth_mm, depth_bias_mm and depth_root_mm per joint (null: never visible) and
// the means over joints seen.
nlohmann::ordered_json split_json(const ErrorSplitScores& s) {
  nlohmann::ordered_json px, dz, bias, root;
  const auto value = [](bool seen, double v) { return seen ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr); };
  for (int i = 0; i < kJoints; ++i) {
    const bool seen = s.n[std::size_t(i)] > 0;
    px[kJointNames[i]] = value(seen, s.image_px[std::size_t(i)]);
    dz[kJointNames[i]] = value(seen, s.depth_mm[std::size_t(i)]);
    bias[kJointNames[i]] = value(seen, s.depth_bias_mm[std::size_t(i)]);
    root[kJointNames[i]] = value(s.n_root[std::size_t(i)] > 0, s.depth_root_mm[std::size_t(i)]);
  }
  return {{"mean_image_px", s.mean_image_px}, {"mean_depth_mm", s.mean_depth_mm}, {"mean_depth_root_mm", s.mean_depth_root_mm},
          {"image_px", px}, {"depth_mm", dz}, {"depth_bias_mm", bias}, {"depth_root_mm", root}};
}

void split_row(std::ostream& o, const char* who, const ErrorSplitScores& s) {
  o << "  " << who << ": mean " << s.mean_image_px << " px / " << s.mean_depth_mm << " mm;";
  for (int i = 0; i < kJoints; ++i) {
    o << " " << kJointNames[i] << " ";
    if (s.n[std::size_t(i)]) o << s.image_px[std::size_t(i)] << "/" << s.depth_mm[std::size_t(i)];
    else o << "n/a";
  }
  o << "\n  " << who << ", depth hip-aligned / signed bias (mm): mean " << s.mean_depth_root_mm << ";";
  for (int i = 0; i < kJoints; ++i) {
    o << " " << kJointNames[i] << " ";
    if (s.n[std::size_t(i)]) {
      if (s.n_root[std::size_t(i)]) o << s.depth_root_mm[std::size_t(i)];
      else o << "n/a";
      o << "/" << std::showpos << s.depth_bias_mm[std::size_t(i)] << std::noshowpos;
    } else {
      o << "n/a";
    }
  }
  o << "\n";
}
}  // namespace

std::string pose_scores_json(const PoseScores& s) { return scores_json(s).dump(); }

std::string eval_json(const EvalResult& r) {
  nlohmann::ordered_json j = scores_json(r.all);
  j["config"] = r.config;
  j["scenes"] = r.scenes;
  j["mask_iou"] = r.mask_iou >= 0 ? nlohmann::ordered_json(r.mask_iou) : nlohmann::ordered_json(nullptr);
  nlohmann::ordered_json pj;
  for (int i = 0; i < kJoints; ++i)
    pj[kJointNames[i]] = r.all.joint_frames[std::size_t(i)] ? nlohmann::ordered_json(r.all.mpjpe_per_joint[std::size_t(i)])
                                                            : nlohmann::ordered_json(nullptr);  // never visible: n/a
  j["mpjpe_per_joint_mm"] = pj;
  nlohmann::ordered_json fj = nlohmann::ordered_json::object();
  for (const auto& [name, s] : r.floors) fj[name] = scores_json(s);
  j["floors"] = fj;
  nlohmann::ordered_json sj = nlohmann::ordered_json::object();
  for (const auto& [view, share] : r.swap_share_by_view) sj[view] = share;
  j["swap_share_by_view"] = sj;
  j["swap_oracle"] = scores_json(r.swap_oracle);
  j["error_split"] = nlohmann::ordered_json::object();
  j["error_split"]["model"] = split_json(r.split);
  if (r.split_per_view_floor) j["error_split"]["per_view_mean_pose_at_hip"] = split_json(*r.split_per_view_floor);
  nlohmann::ordered_json bc;
  for (const auto& [name, values] : r.by_condition)
    for (const auto& [value, s] : values) bc[name][value] = scores_json(s);
  j["by_condition"] = bc;
  const auto by_condition = [](const std::map<std::string, std::map<std::string, double>>& m) {
    nlohmann::ordered_json o = nlohmann::ordered_json::object();
    for (const auto& [name, values] : m)
      for (const auto& [value, iou] : values) o[name][value] = iou;
    return o;
  };
  j["mask_iou_by_condition"] = by_condition(r.mask_iou_by_condition);
  j["mask_iou_off_edge"] = r.mask_iou_off_edge >= 0 ? nlohmann::ordered_json(r.mask_iou_off_edge) : nlohmann::ordered_json(nullptr);
  j["mask_iou_off_edge_by_condition"] = by_condition(r.mask_iou_off_edge_by_condition);
  j["mask_iou_sensor_px"] = r.mask_iou_px >= 0 ? nlohmann::ordered_json(r.mask_iou_px) : nlohmann::ordered_json(nullptr);
  j["mask_iou_sensor_px_by_condition"] = by_condition(r.mask_iou_px_by_condition);
  return j.dump(2) + "\n";
}

std::string frame_poses_csv(const std::vector<FramePose>& poses) {
  std::ostringstream o;
  o << "source,view,window,frame,t_us,fx,fy,cx,cy,true_head_depth_mm";
  for (const char* what : {"", "true_"})
    for (int j = 0; j < kJoints; ++j)
      for (const char* c : {"x", "y", "z"}) o << ',' << what << 'j' << j << '_' << c;
  for (int j = 0; j < kJoints; ++j) o << ",valid" << j;
  o << ",width,height\n" << std::setprecision(7);
  for (const FramePose& p : poses) {
    o << p.source << ',' << p.view << ',' << p.window << ',' << p.frame << ',' << p.t_us << ',' << p.k.fx << ',' << p.k.fy
      << ',' << p.k.cx << ',' << p.k.cy << ',' << p.z_ref;
    for (const Pose13* q : {&p.pred, &p.truth})
      for (const auto& jt : *q)
        for (double v : jt) o << ',' << v;
    for (std::uint8_t v : p.valid) o << ',' << int(v);
    o << ',' << p.k.width << ',' << p.k.height << '\n';
  }
  return o.str();
}

std::string eval_table(const EvalResult& r) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1);
  o << "config " << r.config << ", " << r.scenes << " scenes, " << r.all.frames << " frames\n"
    << "MPJPE " << r.all.mpjpe_mm << " mm, PCK@150 " << std::setprecision(3) << r.all.pck150 << ", AUC " << r.all.auc
    << std::setprecision(1) << "; root-aligned: MPJPE " << r.all.mpjpe_root_mm << " mm, PCK@150 " << std::setprecision(3)
    << r.all.pck150_root << ", AUC " << r.all.auc_root << "; mask IoU "
    << (r.mask_iou >= 0 ? std::to_string(r.mask_iou).substr(0, 5) : std::string("n/a (true masks, or stage 2 reads no mask)"));
  // Pooled over every recording, a mask drawn in a scene with nobody in it counts against
  // the IoU; the recordings with a dancer alone say how well stage 1 outlines a dancer.
  if (const auto p = r.mask_iou_by_condition.find("people"); r.mask_iou >= 0 && p != r.mask_iou_by_condition.end())
    if (const auto dn = p->second.find("dancer"); dn != p->second.end() && p->second.count("nobody"))
      o << " (recordings with a dancer alone: " << std::to_string(dn->second).substr(0, 5) << ")";
  if (r.mask_iou_off_edge >= 0) {
    o << "; off the true outline's edge " << std::to_string(r.mask_iou_off_edge).substr(0, 5);
    if (const auto p = r.mask_iou_off_edge_by_condition.find("people"); p != r.mask_iou_off_edge_by_condition.end())
      if (const auto dn = p->second.find("dancer"); dn != p->second.end() && p->second.count("nobody"))
        o << " (with a dancer: " << std::to_string(dn->second).substr(0, 5) << ")";
    o << "; at the sensor's pixels " << std::to_string(r.mask_iou_px).substr(0, 5);
    if (const auto p = r.mask_iou_px_by_condition.find("people"); p != r.mask_iou_px_by_condition.end())
      if (const auto dn = p->second.find("dancer"); dn != p->second.end() && p->second.count("nobody"))
        o << " (with a dancer: " << std::to_string(dn->second).substr(0, 5) << ")";
  }
  o << "\n";
  o << std::setprecision(1) << "per joint (mm):";
  for (int i = 0; i < kJoints; ++i) {
    o << " " << kJointNames[i] << " ";
    if (r.all.joint_frames[std::size_t(i)]) o << r.all.mpjpe_per_joint[std::size_t(i)];
    else o << "n/a";
  }
  o << "\n";
  if (!r.floors.empty()) {
    o << "floors on the same frames (MPJPE / root-aligned mm):";
    for (const auto& [name, s] : r.floors) o << "  " << name << " " << s.mpjpe_mm << " / " << s.mpjpe_root_mm;
    o << "\n";
  }
  o << "left/right swap would be better on:";
  for (const auto& [view, share] : r.swap_share_by_view) o << "  " << view << " " << std::setprecision(0) << share * 100 << "%";
  o << std::setprecision(1) << " of frames; with the better of each pose and its swap (an oracle): MPJPE "
    << r.swap_oracle.mpjpe_mm << " mm, root-aligned " << r.swap_oracle.mpjpe_root_mm << " mm\n";
  o << "error in the image (sensor px) / in depth (|dz| mm), per joint:\n";
  split_row(o, "model", r.split);
  if (r.split_per_view_floor) split_row(o, "per-view floor", *r.split_per_view_floor);
  for (const auto& [name, values] : r.by_condition) {
    if (name == "scene") {
      // One line per scene would drown the table: the worst few (all are in the JSON).
      std::vector<std::pair<double, std::string>> worst;
      for (const auto& [value, s] : values) worst.emplace_back(s.mpjpe_mm, value);
      std::sort(worst.rbegin(), worst.rend());
      o << "worst scenes (MPJPE mm, of " << worst.size() << "):";
      for (std::size_t i = 0; i < std::min<std::size_t>(5, worst.size()); ++i)
        o << "  " << worst[i].second << " " << worst[i].first;
      o << "\n";
      continue;
    }
    o << name << ":";
    const auto ious = r.mask_iou_by_condition.find(name);
    for (const auto& [value, s] : values) {
      o << "  " << value << " " << s.mpjpe_mm << " mm (" << s.frames << " frames";
      if (ious != r.mask_iou_by_condition.end())
        if (const auto it = ious->second.find(value); it != ious->second.end())
          o << ", IoU " << std::setprecision(3) << it->second << std::setprecision(1);
      o << ")";
    }
    o << "\n";
  }
  return o.str();
}

}  // namespace yelan::train
