#include "engine/run/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "camera/io/event_reader.h"
#include "camera/repr/tore.h"
#include "camera/sim/motion.h"
#include "engine/input.h"
#include "engine/train/pose_norm.h"
#include "kernels/conv_bf16.h"
#include "layers/simple.h"
#include "weights_tools/network_io.h"

namespace yelan::run {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr double kTrainFrameHz = 50;  // the rate the future masks were trained at
constexpr double kFocalPx = camera::sim::kDavis346FocalPx;

// Limb bones over the DHP19 joints: shoulder-elbow, elbow-hand, hip-knee, knee-foot, both sides.
constexpr int kBones[8][2] = {{1, 3}, {3, 7}, {2, 4}, {4, 8}, {5, 9}, {9, 11}, {6, 10}, {10, 12}};

// Mean sigmoid of channel c's logits over the pixels the cut kept (0 where none).
float mean_probability_inside(const layers::Act& logits, int c, const std::vector<float>& keep) {
  const float* p = logits.data + std::size_t(c / 16) * logits.pixels() * 16 + c % 16;
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i] != 0) sum += 1 / (1 + std::exp(-double(p[i * 16]))), ++n;
  return n ? float(sum / double(n)) : 0.f;
}

}  // namespace

float largest_blob_share(const std::vector<float>& mask, int w, int h) {
  if (w <= 0 || h <= 0 || mask.size() != std::size_t(w) * std::size_t(h))
    throw std::invalid_argument("largest_blob_share: a " + std::to_string(w) + "x" + std::to_string(h) + " mask of " +
                                std::to_string(mask.size()) + " pixels");
  std::vector<std::uint8_t> seen(mask.size(), 0);
  std::vector<std::size_t> stack;
  std::size_t total = 0, best = 0;
  for (std::size_t s = 0; s < mask.size(); ++s) {
    if (mask[s] == 0 || seen[s]) continue;
    std::size_t n = 0;
    stack.assign(1, s);
    seen[s] = 1;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      ++n;
      const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const std::size_t j = std::size_t(ny) * std::size_t(w) + std::size_t(nx);
          if (mask[j] != 0 && !seen[j]) seen[j] = 1, stack.push_back(j);
        }
    }
    total += n;
    best = std::max(best, n);
  }
  return total ? float(best) / float(total) : 0.f;
}

double head_depth_from_height(const std::array<std::array<double, 3>, 13>& unit, double height_mm, bool forearms) {
  // The limbs' lengths for this height, as the simulator's bodies have them (Drillis-Contini).
  camera::sim::BodyShape shape;
  shape.height_mm = height_mm;
  const camera::sim::BodyProportions b = camera::sim::body_proportions(shape);
  const double prior = 2 * (b.upper_arm + (forearms ? b.forearm : 0) + b.thigh + b.shank);
  double sum = 0;
  for (const auto& bone : kBones) {
    if (!forearms && (bone[1] == 7 || bone[1] == 8)) continue;  // elbow-hand
    const auto& p = unit[std::size_t(bone[0])];
    const auto& q = unit[std::size_t(bone[1])];
    sum += std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
  }
  return sum > 1e-9 ? prior / sum : 0;
}

struct PosePipeline::Impl {
  weights::Weights w;
  weights::LoadedNetworks nets;
  RunOptions opt;
  camera::ToreVolume tore;
  std::vector<float> vol;  // the TORE at vol_t at the sensor's size, read for pictures alone
  std::int64_t vol_t = 0;
  bool vol_whole = true;
  layers::ActBuf frame, unmasked, window;
  // Where the last tick wrote frame's masked input (box_input); the rest of frame is zero.
  // Starts as the whole frame: nothing is known to be zero until a tick clears it.
  PoseNet::CropBox frame_written{0, 0, std::numeric_limits<int>::max(), std::numeric_limits<int>::max()};
  layers::Act last_in{};
  train::Intrinsics k;
  std::int64_t dt_us, next_tick = std::numeric_limits<std::int64_t>::min();
  std::int64_t latest_tick_us = std::numeric_limits<std::int64_t>::min();
  bool started = false;
  std::uint64_t events_since = 0;
  // stage 1
  bool have_masks = false;
  std::int64_t mask_t = 0;
  std::int64_t idle_recheck_us = 0;
  std::vector<std::vector<float>> masks;  // N binarised masks, H x W
  // Stage 2's masks where they differ from `masks`: the future ones (1..N-1) at
  // run.mask_cut_reused, and with run.mask_grow every one (0..N-1), as cut here and read
  // grown (stage2_grown_masks), with their boxes; an empty entry (or none): stage 2 reads `masks`.
  std::vector<std::vector<float>> stage2_masks;
  std::vector<PoseNet::CropBox> stage2_boxes;
  std::vector<char> stage2_grown;  // whether stage2_grown_masks[c] is made yet
  std::vector<std::vector<float>> stage2_grown_masks;  // with run.mask_grow: stage2_masks[c] grown, made when stage 2 first reads it
  std::vector<input::MaskExtent> extents, stage2_extents;  // of `masks`, of stage2_masks before growth
  std::vector<float> scores;
  std::vector<PoseNet::CropBox> boxes;  // each mask's bounding box
  int in_use = 0;
  int cut_end = 0;  // stage 1's masks 0..cut_end-1 are binarised; the rest stay empty
  int crop = 0;                         // margin; 0: stage 2 on the whole frame
  int mask_crop = 0;                    // margin; 0: stage 1 on the whole frame
  MaskNet::Box last_stage1_crop;        // where stage 1 ran last; empty: the whole frame
  PoseNet::CropBox window_box;          // bidirectional: the union over the window's frames
  // stage 2
  int slot = 0;
  std::vector<std::int64_t> slot_t;
  std::vector<bool> slot_mask_ran;
  std::vector<int> slot_mask_age;
  // What each stored mask says of presence, and what each window slot's mask said.
  struct Cues {
    float share = 0, mean_p = 0, blob = 0, score = 0;
  };
  std::vector<Cues> slot_cues;
  std::vector<Cues> cues;
  PresenceSmoother smoother;
  DepthSmoother depth_smoother;
  JointSmoother joint_smoother;
  double beta = 0.99;
  layers::Bf16Path stage1_path = layers::Bf16Path::none;  // run.bf16 or RunOptions::bf16, and the CPU
  bool stage2_bf16 = false;  // run.pose_bf16 or RunOptions::pose_bf16, on AMX alone
  Pose last;
  bool have_last = false;
  RunStats stats;

  Impl(const std::string& path, int sw, int sh, const RunOptions& o)
      : w(weights::load_weights(path)), nets(w, path), opt(o), tore(sw, sh) {
    const ModelConfig& cfg = nets.cfg;
    if (sw != cfg.sensor_width || sh != cfg.sensor_height)
      throw std::invalid_argument("the events are " + std::to_string(sw) + "x" + std::to_string(sh) + ", the model (" +
                                  path + ") expects " + std::to_string(cfg.sensor_width) + "x" +
                                  std::to_string(cfg.sensor_height));
    if (cfg.representation != "tore")
      throw std::invalid_argument(path + ": config '" + cfg.name + "' reads " + cfg.representation +
                                  " frames; yelan run streams TORE only (the other inputs are baselines for yelan eval)");
    crop = cfg.masked_input ? (o.crop_margin >= 0 ? o.crop_margin : cfg.crop_margin) : 0;
    mask_crop = cfg.runs_stage1() ? (o.mask_crop_margin >= 0 ? o.mask_crop_margin : cfg.mask_crop_margin) : 0;
    if (!(o.rate_hz >= 1 && o.rate_hz <= 1000)) throw std::invalid_argument("rate must be 1..1000 poses per second");
    dt_us = std::llround(1e6 / o.rate_hz);
    vol.resize(tore.volume_size());
    frame.resize(1, cfg.pose_channels(), cfg.height(), cfg.width());
    unmasked.resize(1, cfg.channels, cfg.height(), cfg.width());
    if (cfg.bidirectional) window.resize(cfg.window, cfg.pose_channels(), cfg.height(), cfg.width());
    else nets.pose.set_streaming(true);
    slot_t.resize(std::size_t(cfg.window));
    slot_mask_ran.resize(std::size_t(cfg.window));
    slot_mask_age.resize(std::size_t(cfg.window));
    slot_cues.resize(std::size_t(cfg.window));
    beta = o.beta >= 0 ? o.beta : cfg.run_beta;
    if (o.presence_ab) nets.cfg.presence_a = (*o.presence_ab)[0], nets.cfg.presence_b = (*o.presence_ab)[1];
    if (o.mask_cut) nets.cfg.mask_cut = *o.mask_cut;
    if (o.mask_grow) nets.cfg.mask_grow = *o.mask_grow;
    if (o.presence_tau_s) nets.cfg.presence_tau_s = *o.presence_tau_s;
    smoother = PresenceSmoother(nets.cfg.presence_tau_s);
    if (o.depth_tau_s) nets.cfg.depth_tau_s = *o.depth_tau_s;
    depth_smoother = DepthSmoother(nets.cfg.depth_tau_s);
    if (o.pose_tau_s) nets.cfg.pose_tau_s = *o.pose_tau_s;
    joint_smoother = JointSmoother(nets.cfg.pose_tau_s);
    if (o.depth_forearms) nets.cfg.depth_forearms = *o.depth_forearms;
    if (o.idle_recheck_s) nets.cfg.idle_recheck_s = *o.idle_recheck_s;
    nets.mask.set_bf16(o.bf16.value_or(cfg.run_bf16));
    stage1_path = layers::bf16_path_if(nets.mask.bf16());
    // On AMX alone: stage 2's maps are small, and bf16 pairs on AVX512-BF16 were not measured there.
    stage2_bf16 = o.pose_bf16.value_or(cfg.run_pose_bf16) && layers::bf16_path_if(true) == layers::Bf16Path::amx;
    if (stage1_path == layers::Bf16Path::amx && cfg.mask_max_age_bf16) nets.cfg.mask_max_age = *cfg.mask_max_age_bf16;
    if (stage1_path == layers::Bf16Path::winograd && cfg.mask_max_age_bf16_winograd)
      nets.cfg.mask_max_age = *cfg.mask_max_age_bf16_winograd;
    if (o.mask_max_age) {
      if (*o.mask_max_age < 0) throw std::invalid_argument("mask_max_age must be >= 0 (frames; 0: none)");
      nets.cfg.mask_max_age = *o.mask_max_age;
    }
    if (o.mask_mirror_doubt) {
      if (!ModelConfig::mask_mirror_doubt_ok(*o.mask_mirror_doubt))
        throw std::invalid_argument("the mask mirror's margin must lie in [0, 0.5)");
      nets.cfg.mask_mirror_doubt = *o.mask_mirror_doubt;
    }
    idle_recheck_us = std::llround(nets.cfg.idle_recheck_s * 1e6);
    // Under an age cap K early exit reuses masks 0..K-1 and stage 1's next crop reads mask
    // K's box; the rest are never read, and cutting all 16 twice took 8% of stage 1 in bf16 (perf).
    const int cap = nets.cfg.mask_max_age;
    cut_end = o.cut_every_mask || cap <= 0 ? nets.cfg.n_masks : std::min(cap + 1, nets.cfg.n_masks);
    k = {kFocalPx, kFocalPx, sw / 2.0, sh / 2.0, sw, sh};
    warm_up();
  }

  // The first inference run of each net folds BN into its convs and touches every buffer
  // (50-100 ms); running both once on the empty input here keeps that off the first tick.
  // Stage 1 keeps no state; stage 2's recurrent state is reset after.
  void warm_up() {
    const ModelConfig& cfg = nets.cfg;
    layers::NoGrad no_grad;
    if (cfg.runs_stage1()) nets.mask.forward(unmasked.act);
    if (cfg.runs_stage1() && mask_crop > 0) nets.mask.forward_cropped(unmasked.act, {0, 0, 1, 1});  // its zero frame
    if (cfg.runs_stage1() && cfg.mask_mirror_doubt > 0 && !cfg.mask_mirror) nets.mask.add_mirror(unmasked.act);
    const layers::Act& x = cfg.bidirectional ? window.act : frame.act;
    const int frames = cfg.bidirectional ? cfg.window : 1;
    const layers::Bf16Convs precision(stage2_bf16);  // its weights packed, its empty frame made in its precision
    if (crop > 0) nets.pose.forward_cropped(x, {0, 0, x.w, x.h}, frames);
    else nets.pose.forward(x, frames);
    nets.pose.reset_stream();
  }

  void emit_poses(int frames, const std::function<void(const Pose&)>& out) {
    const ModelConfig& cfg = nets.cfg;
    const std::vector<float>& jn = nets.pose.joints();
    const layers::Act& xy = nets.pose.heatmap(cfg.stages - 1, 0);
    for (int f = 0; f < frames; ++f) {
      std::array<std::array<double, 3>, 13> unit;
      for (int j = 0; j < 13; ++j) {
        const float* q = &jn[(std::size_t(f) * cfg.joints + j) * 3];
        unit[std::size_t(j)] = train::denormalise_joint({q[0], q[1], q[2]}, k, 1.0);
      }
      Pose p;
      p.t_us = slot_t[std::size_t(f)];
      p.mask_ran = slot_mask_ran[std::size_t(f)];
      p.mask_age = slot_mask_age[std::size_t(f)];
      set_presence(p, slot_cues[std::size_t(f)]);
      double z = opt.fixed_depth_mm;
      if (!(z > 0)) {
        z = nets.cfg.depth_scale * head_depth_from_height(unit, opt.body_height_mm, nets.cfg.depth_forearms);
        if (p.person) z = depth_smoother.update(z, p.t_us);
        else depth_smoother.reset();
      }
      // After the depth prior, which was fitted (run.depth_scale) on the tick's own limbs.
      if (p.person) unit = joint_smoother.update(unit, p.t_us);
      else joint_smoother.reset();
      p.head_depth_mm = z;
      double conf = 0;
      for (int j = 0; j < 13; ++j) {
        for (int c = 0; c < 3; ++c) p.joints_mm[std::size_t(j)][std::size_t(c)] = float(unit[std::size_t(j)][std::size_t(c)] * z);
        float peak = 0;
        const float* hm = xy.data + (std::size_t(f) * xy.cb() + j / 16) * xy.pixels() * 16 + j % 16;
        for (std::size_t i = 0; i < xy.pixels(); ++i) peak = std::max(peak, hm[i * 16]);
        conf += peak;
      }
      p.pose_confidence = float(conf / 13);
      if (!p.person)
        for (auto& jt : p.joints_mm) jt.fill(std::numeric_limits<float>::quiet_NaN());
      last = p;
      have_last = true;
      ++stats.poses;
      stats.person_poses += p.person;
      out(p);
    }
  }

  void set_presence(Pose& p, const Cues& c) {
    const ModelConfig& cfg = nets.cfg;
    p.mask_share = c.share;
    p.mask_mean_p = c.mean_p;
    p.mask_blob = c.blob;
    p.mask_score = c.score;
    p.confidence = cfg.runs_stage1() ? float(presence_probability_of_feature(smoother.update(c.share, p.t_us), cfg.presence_a,
                                                                            cfg.presence_b))
                                     : 1.0f;
    p.person = p.confidence >= opt.presence_threshold;
  }
  float presence_of(float share) const {
    return float(presence_probability(share, nets.cfg.presence_a, nets.cfg.presence_b));
  }
  bool in_doubt(float share) const {
    const double d = nets.cfg.mask_mirror_doubt;
    if (d <= 0 || nets.cfg.mask_mirror) return false;  // no margin, or every run mirrored already
    const double p = presence_of(share);
    return p >= d && p <= 1 - d;
  }

  // What stage 2 reads behind mask `use` (its own cut or grown where the config says so), and its box.
  bool has_own_stage2_mask(int use) const {
    return std::size_t(use) < stage2_masks.size() && !stage2_masks[std::size_t(use)].empty();
  }
  const std::vector<float>& stage2_mask(int use) {
    if (!has_own_stage2_mask(use)) return masks[std::size_t(use)];
    if (nets.cfg.mask_grow == 0) return stage2_masks[std::size_t(use)];
    if (!stage2_grown[std::size_t(use)]) {
      stage2_grown_masks.resize(stage2_masks.size());
      stage2_grown_masks[std::size_t(use)] = stage2_masks[std::size_t(use)];
      const layers::Act& m = nets.mask.masks();
      input::grow_mask(stage2_grown_masks[std::size_t(use)], m.h, m.w, nets.cfg.mask_grow);
      stage2_grown[std::size_t(use)] = true;
    }
    return stage2_grown_masks[std::size_t(use)];
  }
  // Stage 1's mask `use` as cut (run.mask_cut, or run.mask_cut_reused for a future one), not grown.
  const std::vector<float>& stage1_mask(int use) const {
    return has_own_stage2_mask(use) ? stage2_masks[std::size_t(use)] : masks[std::size_t(use)];
  }
  const PoseNet::CropBox& stage2_box(int use) const {
    return has_own_stage2_mask(use) ? stage2_boxes[std::size_t(use)] : boxes[std::size_t(use)];
  }

  // The TORE read out at T and downscaled into `unmasked`: only inside `box` (input pixels)
  // where given, the rest left stale (the mask that box bounds zeroes it). The whole volume
  // at the sensor's size is read for pictures alone, on demand (full_tore()).
  void read_tore(std::int64_t T, const PoseNet::CropBox* box) {
    vol_t = T;
    vol_whole = false;
    const int d = nets.cfg.downscale;
    if (box) {
      input::tore_input(tore, T, d, unmasked.act, 0, *box);
      ++stats.tore_box_ticks;
      stats.tore_box_area += frame_share(*box, unmasked.act);
      return;
    }
    input::tore_input(tore, T, d, unmasked.act, 0, camera::PixelRect{0, 0, unmasked.act.w, unmasked.act.h});
  }
  const std::vector<float>& full_tore() {
    if (!vol_whole) tore.readout(vol_t, vol.data()), vol_whole = true;
    return vol;
  }

  // The share of x's frame that b covers, clipped to the frame.
  static double frame_share(const PoseNet::CropBox& b, const layers::Act& x) {
    const PoseNet::CropBox c = b.clipped(x.w, x.h);
    return c.empty() ? 0.0 : double(c.width()) * c.height() / (double(x.w) * x.h);
  }

  PoseNet::CropBox grown(PoseNet::CropBox b) const {
    if (b.empty()) return b;
    return {b.x0 - crop, b.y0 - crop, b.x1 + crop, b.y1 + crop};
  }

  static PoseNet::CropBox unite(const PoseNet::CropBox& a, const PoseNet::CropBox& b) {
    if (a.empty()) return b;
    if (b.empty()) return a;
    return {std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
  }

  // Where stage 1 runs next: its last masks' box (now and the predicted future up to the age
  // cap, all but the empty ones) grown by mask.crop_margin; empty (the whole frame) with the
  // margin 0, before the first run, after one that saw nobody, once the last run is older than
  // its masks' span, and after a cropped run whose masks reach the crop's edge.
  MaskNet::Box stage1_crop(std::int64_t T) const {
    const ModelConfig& cfg = nets.cfg;
    if (mask_crop <= 0 || !have_masks || presence_of(cues[0].share) < opt.presence_threshold) return {};
    if ((T - mask_t) * kTrainFrameHz * 1e-6 >= cfg.n_masks) return {};
    // The masks the run could be reused for: those up to run.mask_max_age (the next run's dancer is
    // where one of them says).
    const int last = cfg.mask_max_age > 0 ? std::min(cfg.mask_max_age, cfg.n_masks - 1) : cfg.n_masks - 1;
    PoseNet::CropBox u;
    for (int c = 0; c <= last && std::size_t(c) < boxes.size(); ++c) u = unite(u, boxes[std::size_t(c)]);
    if (u.empty()) return {};
    // A mask that reaches an edge of the last crop inside the frame may have been cut there (the
    // dancer moved faster than its masks foresaw): the whole frame again.
    const MaskNet::Box& c = last_stage1_crop;
    const int W = unmasked.act.w, H = unmasked.act.h, e = 2;
    if (!c.empty() && ((c.x0 > 0 && u.x0 < c.x0 + e) || (c.y0 > 0 && u.y0 < c.y0 + e) || (c.x1 < W && u.x1 > c.x1 - e) ||
                       (c.y1 < H && u.y1 > c.y1 - e)))
      return {};
    return {u.x0 - mask_crop, u.y0 - mask_crop, u.x1 + mask_crop, u.y1 + mask_crop};
  }

  // Stage 2's masked input into frame, the TORE times mask `use`, as a copy and
  // input::apply_mask over the frame would leave it (a tick's input the same value for value),
  // but over the mask's box alone: outside it the mask is zero, and so is frame once the last
  // tick's box is cleared. A third of the frame's bytes on a dancer, none in an empty room.
  void box_input(int use) {
    const layers::Act& a = frame.act;
    const PoseNet::CropBox& m = stage2_box(use);
    const auto clipped = [&](const PoseNet::CropBox& b) {
      const PoseNet::CropBox c = b.clipped(a.w, a.h);
      return c.empty() ? PoseNet::CropBox{} : c;
    };
    const PoseNet::CropBox old = clipped(frame_written), now = clipped(m);
    layers::zero_window(a, old.y0, old.x0, old.height(), old.width());
    layers::copy_window(unmasked.act, now.y0, now.x0, a, now.y0, now.x0, now.height(), now.width());
    input::apply_mask(a, 0, stage2_mask(use), now);
    frame_written = now;
  }

  void run_stage2(const layers::Act& x, int frames, const PoseNet::CropBox& box) {
    const layers::Bf16Convs precision(stage2_bf16);
    if (crop <= 0) {
      nets.pose.forward(x, frames);
      return;
    }
    const PoseNet::CropBox ran = nets.pose.forward_cropped(x, box, frames);
    stats.crop_area += frame_share(ran, x);
    ++stats.crop_runs;
  }

  void tick(std::int64_t T, const std::function<void(const Pose&)>& out) {
    const ModelConfig& cfg = nets.cfg;
    const auto t_tick = Clock::now();
    ++stats.ticks;
    latest_tick_us = T;
    if (opt.skip_empty && events_since == 0 && have_last && !cfg.bidirectional) {
      Pose p = last;
      p.t_us = T;
      p.stale = true;
      p.mask_ran = false;
      ++stats.stale;
      ++stats.poses;
      stats.person_poses += p.person;
      out(p);
      return;
    }
    events_since = 0;
    layers::NoGrad no_grad;
    // Stage 1, early exit: reuse the stored future mask while its score stays >= beta.
    const int idx = have_masks ? int(std::llround(double(T - mask_t) * kTrainFrameHz * 1e-6)) : -1;
    // A stored future mask that says nobody is there is not reused, however sure its score:
    // a net that saw an empty room is confidently wrong about the next 300 ms once someone
    // walks in (a dancer was missed on the first 16 ticks of the demo). A run that saw nobody
    // in the current frame is redone once run.idle_recheck_s has passed (0: on the next tick;
    // at most the future masks' span), its current mask kept meanwhile: its future masks
    // would predict someone the net did not see.
    bool run_mask = cfg.runs_stage1() && (!have_masks || idx < 0 || idx >= cfg.n_masks || beta > 1);
    bool hold_current = false;
    if (cfg.runs_stage1() && !run_mask) {
      if (presence_of(cues[0].share) < opt.presence_threshold) {
        run_mask = T - mask_t >= idle_recheck_us;
        hold_current = !run_mask;
      } else {
        run_mask = scores[std::size_t(idx)] < beta || presence_of(cues[std::size_t(idx)].share) < opt.presence_threshold ||
                   (cfg.mask_max_age > 0 && idx >= cfg.mask_max_age);
      }
    }
    int use = hold_current ? 0 : idx;
    auto t0 = Clock::now();
    // Stage 2 alone reads this tick's TORE, behind a stored mask: only the mask's box (with
    // pose.outside_input, the box of stage 2's crop: it reads the events around the mask too).
    const bool box_only = !run_mask && opt.tore_box && cfg.runs_stage1() && cfg.masked_input && !cfg.bidirectional &&
                          (!cfg.outside_input || crop > 0);
    PoseNet::CropBox read_box = box_only ? stage2_box(use) : PoseNet::CropBox{};
    if (cfg.outside_input) read_box = grown(read_box);
    read_tore(T, box_only ? &read_box : nullptr);
    stats.times.tore_ms.push_back(ms_since(t0));
    t0 = Clock::now();
    if (run_mask) {
      const MaskNet::Box s1_box = stage1_crop(T);
      last_stage1_crop = {};
      if (s1_box.empty()) {
        nets.mask.forward(unmasked.act);
      } else {
        const MaskNet::Box ran = nets.mask.forward_cropped(unmasked.act, s1_box);
        const double share = frame_share({ran.x0, ran.y0, ran.x1, ran.y1}, unmasked.act);
        stats.mask_crop_area += share;
        ++stats.mask_crop_runs;
        if (share < 1) last_stage1_crop = ran;
      }
      const layers::Act& m = nets.mask.masks();
      input::mask_cut_all(m, 0, float(cfg.mask_cut), masks, extents, 0, cut_end);
      if (in_doubt(float(extents[0].kept) / float(m.pixels()))) {
        // run.mask_mirror's margin: the mirrored run only where presence hangs on this mask.
        nets.mask.add_mirror(unmasked.act);
        input::mask_cut_all(m, 0, float(cfg.mask_cut), masks, extents, 0, cut_end);
        ++stats.mirror_runs;
      }
      scores = nets.mask.scores();
      boxes.assign(std::size_t(cfg.n_masks), PoseNet::CropBox{});
      cues.assign(std::size_t(cfg.n_masks), Cues{});
      for (int c = 0; c < cfg.n_masks; ++c) {
        const input::MaskExtent& e = extents[std::size_t(c)];
        boxes[std::size_t(c)] = {e.x0, e.y0, e.x1, e.y1};
        Cues& q = cues[std::size_t(c)];
        q.share = float(e.kept) / float(m.pixels());
        if (opt.stage1_cues && c < cut_end) {
          q.mean_p = mean_probability_inside(m, c, masks[std::size_t(c)]);
          q.blob = largest_blob_share(masks[std::size_t(c)], m.w, m.h);
        }
        q.score = scores[std::size_t(c)];
      }
      stage2_masks.clear();
      stage2_grown.clear();
      if (cfg.reused_mask_cut() != cfg.mask_cut || cfg.mask_grow > 0) {
        input::mask_cut_all(m, 0, float(cfg.reused_mask_cut()), stage2_masks, stage2_extents, 1, cut_end);
        if (cfg.mask_grow > 0) {
          stage2_masks[0] = masks[0];
          stage2_extents[0] = extents[0];
        }
        // A mask grown by r has its box grown by r (clipped to the frame); the masks themselves
        // are grown when stage 2 first reads one (stage2_mask), one a tick, not N a run.
        const int r = cfg.mask_grow;
        stage2_boxes.assign(std::size_t(cfg.n_masks), PoseNet::CropBox{});
        for (int c = 0; c < cfg.n_masks; ++c) {
          const input::MaskExtent& e = stage2_extents[std::size_t(c)];
          if (e.kept > 0)
            stage2_boxes[std::size_t(c)] = {std::max(e.x0 - r, 0), std::max(e.y0 - r, 0), std::min(e.x1 + r, m.w),
                                            std::min(e.y1 + r, m.h)};
        }
        stage2_grown.assign(std::size_t(cfg.n_masks), 0);
      }
      mask_t = T;
      have_masks = true;
      use = 0;
      ++stats.mask_runs;
    }
    stats.times.stage1_ms.push_back(ms_since(t0));
    if (run_mask) stats.stage1_run_ms.push_back(stats.times.stage1_ms.back());
    // Masked TORE (the whole TORE where stage 1 only decides presence) -> stage 2.
    t0 = Clock::now();
    const layers::Act& dst = cfg.bidirectional ? window.act : frame.act;
    const int n = cfg.bidirectional ? slot : 0;
    const std::size_t per_frame = std::size_t(unmasked.act.cb()) * unmasked.act.pixels() * 16;
    in_use = use;
    if (cfg.masked_input && !cfg.outside_input && !cfg.bidirectional && cfg.runs_stage1()) {
      box_input(use);
    } else {
      std::copy_n(unmasked.act.data, per_frame, dst.data + std::size_t(n) * per_frame);
      if (cfg.masked_input) input::mask_stage2_input(dst, n, stage2_mask(use), cfg.outside_input, crop);
    }
    last_in = {dst.data + std::size_t(n) * per_frame, 1, dst.c, dst.h, dst.w};
    slot_t[std::size_t(slot)] = T;
    slot_mask_ran[std::size_t(slot)] = run_mask;
    slot_mask_age[std::size_t(slot)] = cfg.runs_stage1() ? use : 0;
    slot_cues[std::size_t(slot)] = cfg.runs_stage1() ? cues[std::size_t(use)] : Cues{1, 1, 1, 1};
    const PoseNet::CropBox box =
        !cfg.masked_input ? PoseNet::CropBox{} : grown(stage2_box(use));
    int ready = 0;
    if (!cfg.bidirectional) {
      if (slot == 0) nets.pose.reset_stream();  // windows of S ticks, as trained
      run_stage2(frame.act, 1, box);
      slot_t[0] = T;
      slot_mask_ran[0] = run_mask;
      slot_mask_age[0] = slot_mask_age[std::size_t(slot)];
      slot_cues[0] = slot_cues[std::size_t(slot)];
      slot = (slot + 1) % cfg.window;
      ready = 1;
    } else {
      window_box = slot == 0 ? box : unite(window_box, box);
      if (++slot == cfg.window) {
        run_stage2(window.act, cfg.window, window_box);
        slot = 0;
        ready = cfg.window;
      }
    }
    stats.times.stage2_ms.push_back(ms_since(t0));
    stats.times.tick_ms.push_back(ms_since(t_tick));
    // After the clocks: writing the poses (CSV rows, pictures) is the caller's time.
    if (ready) emit_poses(ready, out);
  }
};

PosePipeline::PosePipeline(const std::string& weights, int sw, int sh, const RunOptions& opt)
    : impl_(std::make_unique<Impl>(weights, sw, sh, opt)) {}
PosePipeline::~PosePipeline() = default;

void PosePipeline::push(std::span<const camera::Event> events, const std::function<void(const Pose&)>& out) {
  Impl& m = *impl_;
  for (std::size_t i = 0; i < events.size();) {
    const camera::Event& e = events[i];
    if (!m.started) {
      m.started = true;
      m.smoother.start_empty(e.t);
      m.next_tick = e.t + m.dt_us;
      if (m.opt.tick_origin_us) {
        // The first tick at or after the event.
        const std::int64_t o = *m.opt.tick_origin_us;
        m.next_tick = o + (e.t - o) / m.dt_us * m.dt_us;
        while (m.next_tick < e.t) m.next_tick += m.dt_us;
        while (m.next_tick - m.dt_us >= e.t) m.next_tick -= m.dt_us;
      }
    }
    // A gap of more than 2 s (a paused recording): skip to the tick before this event,
    // starting a fresh window and mask, instead of running the networks on empty ticks.
    if (e.t - m.next_tick > 2'000'000) {
      const std::int64_t skip = (e.t - m.next_tick) / m.dt_us;
      m.next_tick += skip * m.dt_us;
      m.stats.gap_ticks += std::uint64_t(skip);
      m.slot = 0;
      m.have_masks = false;
      m.smoother.start_empty(m.next_tick - m.dt_us);  // one period before the first tick after the gap
      m.depth_smoother.reset();
      m.joint_smoother.reset();
    }
    while (e.t > m.next_tick) {
      m.tick(m.next_tick, out);
      m.next_tick += m.dt_us;
    }
    // e and the events after it up to the next tick go into the volume in one call: its K-specialised
    // loop (one event at a time, the FIFO shift of a runtime K was a library memmove per event, 7% of
    // `yelan run` on a recording of 6 M events/s).
    std::size_t j = i + 1;
    while (j < events.size() && events[j].t <= m.next_tick) ++j;
    m.tore.update(events.subspan(i, j - i));
    m.events_since += j - i;
    m.stats.events += j - i;
    i = j;
  }
}

void PosePipeline::finish(std::int64_t t_us, const std::function<void(const Pose&)>& out) {
  Impl& m = *impl_;
  if (!m.started) return;
  while (m.next_tick <= t_us) {
    m.tick(m.next_tick, out);
    m.next_tick += m.dt_us;
  }
  // A partial bidirectional window: run it shorter rather than drop its poses.
  if (m.nets.cfg.bidirectional && m.slot > 0) {
    layers::NoGrad no_grad;
    const layers::Act part{m.window.act.data, m.slot, m.window.act.c, m.window.act.h, m.window.act.w};
    m.run_stage2(part, m.slot, m.window_box);
    const int n = m.slot;
    m.slot = 0;
    m.emit_poses(n, out);
  }
}

const RunStats& PosePipeline::stats() const { return impl_->stats; }
std::string PosePipeline::config_name() const { return impl_->nets.cfg.name; }
std::array<double, 2> PosePipeline::presence_ab() const { return {impl_->nets.cfg.presence_a, impl_->nets.cfg.presence_b}; }
double PosePipeline::beta() const { return impl_->beta; }
bool PosePipeline::stage1_bf16() const { return impl_->stage1_path != layers::Bf16Path::none; }
bool PosePipeline::stage2_bf16() const { return impl_->stage2_bf16; }
std::string PosePipeline::stage1_precision() const { return layers::bf16_path_name(impl_->stage1_path); }
int PosePipeline::mask_max_age() const { return impl_->nets.cfg.mask_max_age; }

double presence_feature(double share) { return std::log(std::max(0.0, share) + 0.001); }
double presence_probability_of_feature(double x, double a, double b) { return 1 / (1 + std::exp(-(a * x + b))); }
double presence_probability(double share, double a, double b) {
  return presence_probability_of_feature(presence_feature(share), a, b);
}

void PresenceSmoother::start_empty(std::int64_t t_us) {
  have_ = true;
  x_ = presence_feature(0);
  t_ = t_us;
}

namespace {
// One step of an exponential average with time constant tau_us; the first tick, no
// smoothing, or time going backwards (a new recording) starts afresh from x.
void exp_average(double& avg, bool& have, std::int64_t& t_prev, double x, std::int64_t t_us, double tau_us) {
  if (!have || tau_us <= 0 || t_us < t_prev) avg = x;
  else avg += (1 - std::exp(-double(t_us - t_prev) / tau_us)) * (x - avg);
  have = true;
  t_prev = t_us;
}
}  // namespace

double PresenceSmoother::update(double share, std::int64_t t_us) {
  exp_average(x_, have_, t_, presence_feature(share), t_us, tau_us_);
  return x_;
}

JointSmoother::Skeleton JointSmoother::update(const Skeleton& joints, std::int64_t t_us) {
  for (const auto& j : joints)
    for (double v : j)
      if (!std::isfinite(v)) return joints;
  if (!have_ || tau_us_ <= 0 || t_us < t_) {
    x_ = joints;
  } else {
    const double a = 1 - std::exp(-double(t_us - t_) / tau_us_);
    for (std::size_t j = 0; j < x_.size(); ++j)
      for (std::size_t c = 0; c < 3; ++c) x_[j][c] += a * (joints[j][c] - x_[j][c]);
  }
  have_ = true;
  t_ = t_us;
  return x_;
}

double DepthSmoother::update(double depth_mm, std::int64_t t_us) {
  if (!(depth_mm > 0) || !std::isfinite(depth_mm)) return depth_mm;
  exp_average(x_, have_, t_, std::log(depth_mm), t_us, tau_us_);
  return std::exp(x_);
}
const std::vector<float>& PosePipeline::last_tore() const { return impl_->full_tore(); }
const std::vector<float>& PosePipeline::last_mask() const {
  static const std::vector<float> none;
  return impl_->masks.empty() ? none : impl_->stage2_mask(std::max(0, impl_->in_use));
}
const std::vector<float>& PosePipeline::last_stage1_mask() const {
  static const std::vector<float> none;
  return impl_->masks.empty() ? none : impl_->stage1_mask(std::max(0, impl_->in_use));
}
const layers::Act& PosePipeline::last_input() const { return impl_->last_in; }
const std::vector<std::vector<float>>& PosePipeline::stored_masks() const { return impl_->masks; }
const std::vector<float>& PosePipeline::stored_scores() const { return impl_->scores; }
const layers::Act& PosePipeline::stage1_logits() const { return impl_->nets.mask.masks(); }
int PosePipeline::mask_downscale() const { return impl_->nets.cfg.downscale; }
double PosePipeline::focal_px() const { return kFocalPx; }
bool PosePipeline::causal() const { return !impl_->nets.cfg.bidirectional; }
std::int64_t PosePipeline::latest_tick_us() const { return impl_->latest_tick_us; }

double run_file(PosePipeline& pipe, const std::string& path, std::int64_t end_us, const std::function<void(const Pose&)>& out) {
  using Clock = std::chrono::steady_clock;
  auto reader = camera::open_event_file(path);
  std::vector<camera::Event> ev;
  double seconds = 0;
  while (true) {
    ev.clear();
    if (reader->read_until(ev, end_us, 1 << 20) == 0) break;
    const auto t0 = Clock::now();
    pipe.push(ev, out);
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  const auto t0 = Clock::now();
  pipe.finish(end_us, out);
  return seconds + std::chrono::duration<double>(Clock::now() - t0).count();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5))];
}

double early_exit_saved_ms(const RunStats& s) {
  if (s.stage1_run_ms.empty()) return 0;
  const std::uint64_t with_events = s.ticks - s.stale;
  const std::uint64_t reused = with_events > s.mask_runs ? with_events - s.mask_runs : 0;
  return double(reused) * percentile(s.stage1_run_ms, 0.5);
}

double crop_share(const RunStats& s) { return s.crop_runs ? s.crop_area / double(s.crop_runs) : 1.0; }

std::string pose_csv_header() {
  std::string h = "t_us";
  for (const char* n : camera::sim::kJointNames)
    for (const char* c : {"x", "y", "z"}) h += std::string(",") + n + "_" + c;
  return h + ",confidence,mask_ran,person,pose_confidence,mask_share,mask_age";
}

std::string pose_csv_row(const Pose& p) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(1);
  o << p.t_us;
  for (const auto& j : p.joints_mm) {
    if (p.person) o << "," << j[0] << "," << j[1] << "," << j[2];
    else o << ",,,";
  }
  o.precision(4);
  o << "," << p.confidence << "," << (p.mask_ran ? 1 : 0) << "," << (p.person ? 1 : 0) << "," << p.pose_confidence << ","
    << p.mask_share << "," << p.mask_age;
  return o.str();
}

}  // namespace yelan::run
