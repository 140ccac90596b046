// `yelan weights inspect|diff|verify`: our HDF5 weights files (weights_tools/). Bad input
// (a WeightsError) exits 2 with every problem on its own line; `diff` exits 1 when the
// files differ beyond --tol, like diff(1).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <cstdio>
#include <set>
#include <sstream>

#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"
#include "engine/cli/vet_recordings.h"
#include "engine/run/early_exit.h"
#include "engine/run/presence.h"
#include "camera/sim/recording_windows.h"
#include "engine/model_config.h"
#include "weights_tools/manifest.h"
#include "weights_tools/network_io.h"
#include "weights_tools/parse_json.h"
#include "weights_tools/weights_file.h"
#include "weights_tools/widen.h"

namespace yelan::cli {
namespace {

using weights::TensorInfo;
using weights::WeightsReader;

constexpr int kDiffer = 1;

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

struct GroupCounts {
  std::size_t tensors = 0;
  std::int64_t parameters = 0, values = 0;
};

GroupCounts counts(const std::vector<TensorInfo>& list) {
  GroupCounts c;
  for (const TensorInfo& t : list) {
    ++c.tensors;
    const std::int64_t n = weights::element_count(t.shape);
    c.values += n;
    if (weights::is_parameter(t.name)) c.parameters += n;
  }
  return c;
}

int inspect(const Args& args, std::ostream& out) {
  args.expect_positionals(1, 1);
  WeightsReader r(args.positionals()[0]);
  const nlohmann::ordered_json config = weights::parse_json(r.config_json());
  if (args.flag("--json")) {
    nlohmann::ordered_json doc = {{"file", r.path()}, {"format", weights::kFormat}, {"version", r.version()},
                                  {"config", config}, {"groups", nlohmann::ordered_json::object()}};
    for (const std::string& g : weights::group_names()) {
      const GroupCounts c = counts(r.tensors(g));
      nlohmann::ordered_json shapes = nlohmann::ordered_json::object();
      for (const TensorInfo& t : r.tensors(g)) shapes[t.name] = t.shape;
      doc["groups"][g] = {{"tensors", c.tensors}, {"parameters", c.parameters}, {"values", c.values}, {"shapes", shapes}};
    }
    // Names and paths are bytes: what is not UTF-8 is shown as U+FFFD, never refused.
    out << doc.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << "\n";
    return kOk;
  }
  out << "file:    " << r.path() << "\n"
      << "format:  " << weights::kFormat << ", version " << r.version() << "\n"
      << "config:  " << config.dump() << "\n";
  for (const std::string& g : weights::group_names()) {
    const GroupCounts c = counts(r.tensors(g));
    out << g << ":    " << c.tensors << " tensors, " << c.parameters << " parameters, " << c.values
        << " values with BN buffers\n";
  }
  for (const std::string& g : weights::group_names())
    for (const TensorInfo& t : r.tensors(g)) out << g << "/" << t.name << " " << weights::shape_text(t.shape) << "\n";
  return kOk;
}

// Largest |a - b|; a NaN on one side only is an infinite difference, NaN on both none.
double max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool na = std::isnan(a[i]), nb = std::isnan(b[i]);
    double d = 0;
    if (na != nb) d = INFINITY;
    else if (!na) d = std::fabs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
    worst = std::max(worst, d);
  }
  return worst;
}

double parse_tol(const Args& args) {
  const std::string s = args.value_or("--tol", "0");
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !(v >= 0) || !std::isfinite(v))
    throw UsageError("--tol expects a finite number >= 0, got '" + s + "'");
  return v;
}

int diff(const Args& args, std::ostream& out) {
  args.expect_positionals(2, 2);
  const double tol = parse_tol(args);
  const bool all = args.flag("--all");
  WeightsReader a(args.positionals()[0]), b(args.positionals()[1]);
  std::size_t compared = 0, differing = 0, only_a = 0, only_b = 0, shapes = 0;
  double worst = 0;
  std::string worst_name;
  for (const std::string& g : weights::group_names()) {
    std::set<std::string> names;
    for (const TensorInfo& t : a.tensors(g)) names.insert(t.name);
    for (const TensorInfo& t : b.tensors(g)) names.insert(t.name);
    for (const std::string& name : names) {
      const TensorInfo* ta = a.find(g, name);
      const TensorInfo* tb = b.find(g, name);
      const std::string full = g + "/" + name;
      if (!tb) {
        out << "only in A: " << full << "\n";
        ++only_a;
        continue;
      }
      if (!ta) {
        out << "only in B: " << full << "\n";
        ++only_b;
        continue;
      }
      if (ta->shape != tb->shape) {
        out << "shape differs: " << full << " " << weights::shape_text(ta->shape) << " vs "
            << weights::shape_text(tb->shape) << "\n";
        ++shapes;
        continue;
      }
      const double d = max_abs_diff(a.read(*ta), b.read(*tb));
      ++compared;
      if (worst_name.empty() || d > worst) {
        worst = d;
        worst_name = full;
      }
      if (d > tol) ++differing;
      if (all || d > tol) out << full << " max |a-b| " << number(d) << "\n";
    }
  }
  if (weights::parse_json(a.config_json()) != weights::parse_json(b.config_json())) out << "config differs\n";
  out << "summary: " << compared << " tensors compared, " << differing << " differ by more than " << number(tol)
      << ", max |a-b| " << number(worst) << (worst_name.empty() ? "" : " (" + worst_name + ")") << "; " << only_a
      << " only in A, " << only_b << " only in B, " << shapes << " shapes differ\n";
  return differing + only_a + only_b + shapes > 0 ? kDiffer : kOk;
}

// Dotted paths of the leaves where two JSON objects differ ("input.window").
void json_differences(const nlohmann::ordered_json& a, const nlohmann::ordered_json& b, const std::string& at,
                      std::vector<std::string>& out) {
  if (a.is_object() && b.is_object()) {
    std::set<std::string> keys;
    for (const auto& m : a.items()) keys.insert(m.key());
    for (const auto& m : b.items()) keys.insert(m.key());
    for (const std::string& k : keys) {
      const std::string path = at.empty() ? k : at + "." + k;
      if (!a.contains(k) || !b.contains(k)) out.push_back(path);
      else json_differences(a.at(k), b.at(k), path, out);
    }
  } else if (a != b) {
    out.push_back(at);
  }
}

int verify(const Args& args, std::ostream& out, std::ostream& err) {
  args.expect_positionals(1, 1);
  const auto config = args.value("--config");
  if (!config) throw UsageError("weights verify needs --config NAME|FILE (see 'yelan weights --help')");
  const weights::Manifest m = weights::find_manifest(*config);
  WeightsReader r(args.positionals()[0]);
  weights::verify(r, m);
  std::vector<std::string> differ;
  json_differences(weights::parse_json(r.config_json()), weights::parse_json(m.config_json), "", differ);
  std::string fields;
  for (const std::string& d : differ)
    if (d != "description") fields.append(fields.empty() ? "" : ", ").append(d);
  if (!fields.empty())
    err << "yelan: warning: " << r.path() << ": its config differs from " << m.path << " in " << fields
        << " (the tensors match)\n";
  out << "ok: " << r.path() << " holds every tensor of config '" << m.config_name << "' with its shape";
  for (const std::string& g : weights::group_names()) {
    const GroupCounts c = counts(r.tensors(g));
    out << "; " << g << " " << c.tensors << " tensors, " << c.parameters << " parameters";
  }
  out << "\n";
  return kOk;
}

// The mask group of one file and the pose group of another (trained in separate stages)
// into one model file. Both nets read the same input, so the input sections must agree; the
// result keeps the pose file's config (an ablation of the pose net can take the mask net of
// the full model), whose mask section must then describe the mask net, or --config's, which
// must describe both (a mask net of another width joins a pose net that way).
int combine(const Args& a, std::ostream& out) {
  a.expect_positionals(0, 0);
  const auto m = a.value("--mask"), p = a.value("--pose"), o = a.value("-o");
  if (!m || !p || !o) throw UsageError("weights combine needs --mask A.h5 --pose B.h5 -o OUT.h5");
  check_output("-o", *o, {*m, *p, a.value_or("--config", "")});
  const weights::Weights wm = weights::load_weights(*m), wp = weights::load_weights(*p);
  const auto cm = weights::parse_json(wm.config_json), cp = weights::parse_json(wp.config_json);
  // The sections that shape the networks; mask.role says only what stage 1's output is for,
  // mask.crop_margin only where it runs.
  const auto shape = [](auto d, const char* key) {
    auto s = d.contains(key) ? d.at(key) : decltype(d)();
    if (s.is_object() && std::string(key) == "mask") s.erase("role"), s.erase("crop_margin");
    return s;
  };
  // Without --config the pose file's config describes the result, so it must describe the mask
  // net too; with it, --config must (a mask net of another width joins a pose net that way).
  const bool own_config = a.value("--config").has_value();
  for (const char* key : {"input", "mask"}) {
    if (own_config && std::string(key) == "mask") continue;
    if (!cm.contains(key) || !cp.contains(key) || shape(cm, key) != shape(cp, key))
      throw UsageError("weights combine: " + *m + " and " + *p + " differ in the config's '" + key + "' section, so " +
                       (std::string(key) == "input" ? "the mask net does not fit the pose net's input"
                                                    : "the pose file's config does not describe the mask net (give --config)"));
  }
  weights::Weights w = wp;
  w.groups["mask"] = wm.groups.at("mask");
  if (const auto c = a.value("--config")) {
    // A config for inference settings (pose.crop_margin): it must describe the same networks.
    const ModelConfig nc = load_model_config(*c);
    const auto cn = weights::parse_json(nc.json);
    for (const char* key : {"input", "mask"})
      if (!cn.contains(key) || shape(cn, key) != shape(cm, key))
        throw UsageError("weights combine: --config " + *c + " differs from " + *m + " in the '" + key + "' section");
    // Strides 8 and 4 have the same tensors: only the config tells the networks apart.
    if (nc.head_stride != parse_model_config(wp.config_json, *p).head_stride)
      throw UsageError("weights combine: --config " + *c + " has another pose.head_stride than " + *p +
                       " (the same tensors, another network: train it at that stride)");
    w.config_json = nc.json;
    try {
      const weights::LoadedNetworks fits(w, *c);
    } catch (const std::exception& e) {
      throw UsageError("weights combine: the tensors do not fit --config " + *c + ": " + e.what());
    }
  }
  weights::save_weights(*o, w);
  out << "wrote " << *o << ": mask from " << *m << ", pose from " << *p
      << (a.value("--config") ? ", config from " + *a.value("--config") : std::string()) << "\n";
  return kOk;
}

// What widen and narrow share: W and the target config read, and the changed groups checked
// against the config before anything is written. The config's run settings replace W's
// (calibrate after training).
struct Reshape {
  std::string in, config, out;
  weights::Weights w;
  ModelConfig from, to;
};

Reshape read_reshape(const Args& a, const std::string& usage) {
  a.expect_positionals(0, 0);
  const auto in = a.value("--weights"), name = a.value("--config"), o = a.value("-o");
  if (!in || !name || !o) throw UsageError(usage);
  check_output("-o", *o, {*in, *name});
  Reshape r{*in, *name, *o, {}, {}, {}};
  // A bad config's ConfigError reaches cli.cpp's handler: exit 2 with its message.
  r.to = load_model_config(*name);
  r.w = weights::load_weights(*in);
  r.from = parse_model_config(r.w.config_json, *in + ": attribute config");
  return r;
}

// misfit: what failed to fit when the config refuses the result ("pose group does").
void write_reshape(Reshape& r, const std::string& verb, const std::string& misfit) {
  r.w.config_json = r.to.json;
  try {
    const weights::LoadedNetworks fits(r.w, r.in);
  } catch (const std::exception& e) {
    throw UsageError("weights " + verb + ": " + r.in + "'s " + misfit + " not fit --config " + r.config + ": " + e.what());
  }
  weights::save_weights(r.out, r.w);
}

// A trained stage 1 in a wider mask net that computes the same (weights_tools/widen.h), with
// the pose group as it was: the start of a training at the new width.
int widen(const Args& a, std::ostream& out) {
  const int seed = a.int_value_or("--seed", 0, 0, 2147483647);  // a bad value said before any file is read
  Reshape r = read_reshape(a, "weights widen needs --weights OLD.h5 --config NAME|FILE -o OUT.h5 [--seed N]");
  const ModelConfig &from = r.from, &to = r.to;
  const bool mask = to.mask_width != from.mask_width, wider = to.pose_width != from.pose_width || to.hidden != from.hidden,
             outside = to.outside_input != from.outside_input, pose = wider || outside;
  if (!mask && !pose)
    throw UsageError("weights widen: config " + to.name +
                     " has the same mask.width_mult, pose.width_mult, pose.hidden and pose.outside_input as " + r.in +
                     "; nothing to widen");
  if (mask) r.w.groups["mask"] = weights::widen_mask_group(r.w.groups["mask"], from, to, std::uint64_t(seed) * 2 + 1, r.in);
  if (pose) r.w.groups["pose"] = weights::widen_pose_group(r.w.groups["pose"], from, to, std::uint64_t(seed) * 2 + 2, r.in);
  write_reshape(r, "widen", mask && pose ? "widened groups do" : mask ? "pose group does" : "mask group does");
  out << "wrote " << r.out << ":";
  if (mask)
    out << " mask net widened from width_mult " << from.mask_width << " to " << to.mask_width << " (" << from.unet_width(0)
        << " -> " << to.unet_width(0) << " channels at the top level; the same outputs)" << (pose ? ";" : ", pose from " + r.in + ",");
  if (wider)
    out << " pose net widened from width_mult " << from.pose_width << " to " << to.pose_width << " (" << from.resnet_mid() << " -> "
        << to.resnet_mid() << " channels into the ConvLSTM, hidden " << from.hidden << " -> " << to.hidden << ")";
  if (outside)
    out << (wider ? " and" : " pose net") << " given the input outside the mask (pose.outside_input: " << from.pose_channels()
        << " -> " << to.pose_channels() << " input channels, the new ones read by zero weights)";
  if (pose) out << "; the same outputs" << (mask ? "," : ", mask from " + r.in + ",");
  out << " config " << to.name << " (its run settings, not " << r.in << "'s: calibrate after training)\n";
  return kOk;
}

// A trained stage 1 cut to a narrower mask net (weights_tools/widen.h: the first channels of
// every layer kept), with the pose group as it was: the start of a training at that width.
int narrow(const Args& a, std::ostream& out) {
  Reshape r = read_reshape(a, "weights narrow needs --weights OLD.h5 --config NAME|FILE -o OUT.h5");
  const ModelConfig &from = r.from, &to = r.to;
  if (to.pose_width != from.pose_width || to.hidden != from.hidden || to.outside_input != from.outside_input)
    throw UsageError("weights narrow: config " + to.name + " changes the pose net; narrowing cuts the mask net alone");
  r.w.groups["mask"] = weights::narrow_mask_group(r.w.groups["mask"], from, to, r.in);
  write_reshape(r, "narrow", "pose group does");
  out << "wrote " << r.out << ": mask net cut from width_mult " << from.mask_width << " to " << to.mask_width << " ("
      << from.unet_width(0) << " -> " << to.unet_width(0) << " channels at the top level, the first of each layer kept; "
      << "not the same outputs: train it), pose from " << r.in << ", config " << to.name
      << " (its run settings, not " << r.in << "'s: calibrate after training)\n";
  return kOk;
}

// What smoothing the presence feature over time would buy on the same ticks: each time
// constant refitted, its hit and false-alarm rates, and how long the verdict takes to flip
// when a dancer of the median dancer tick's share appears in an empty picture or leaves it.
void print_smoothing_sweep(const std::vector<run::PresenceSample>& samples, double chosen, std::ostream& out) {
  std::vector<double> dancer_shares;
  for (const auto& s : samples)
    if (s.person) dancer_shares.push_back(s.share);
  const double typical = run::percentile(dancer_shares, 0.5);
  out << std::fixed << std::setprecision(1) << "presence smoothing (tau_s, refitted on these ticks: dancer ticks called person, "
      << "empty ticks called person, seconds to call a dancer of share " << std::setprecision(3) << typical
      << " who appears, and one who leaves):\n";
  for (double tau : {0.0, 0.05, 0.1, 0.2, 0.3, 0.5}) {
    const run::PresenceFit f = run::fit_presence(samples, tau);
    const run::PresenceReport r = run::presence_report(samples, f.a, f.b, 0.5, tau);
    out << std::setprecision(2) << "  " << tau << ": " << std::setprecision(1) << 100 * r.hit_rate << "%, "
        << 100 * r.false_alarm_rate << "%, " << std::setprecision(2) << run::presence_latency_s(f.a, f.b, tau, 0, typical)
        << " s, " << run::presence_latency_s(f.a, f.b, tau, typical, 0) << " s" << (tau == chosen ? "  (in use)" : "") << "\n";
  }
}

// Fits the presence calibration (and stores a beta) for `yelan run`, on the validation
// recordings of a dataset: every tick through the deployed pipeline.
int calibrate(const Args& a, std::ostream& out, std::ostream& err) {
  a.expect_positionals(0, 0);
  const auto w = a.value("--weights"), data = a.value("--data"), o = a.value("-o");
  if (!w || !data || !o) throw UsageError("weights calibrate needs --weights W --data DIR -o OUT.h5");
  const double seconds = a.number_or("--seconds", 3, 0.1, 3600);
  const double skip = a.number_or("--skip", 0.5, 0, 3600);
  const double rate = a.number_or("--rate", 50, 1, 1000);
  const std::optional<std::string> beta = a.value("--beta");
  const double beta_v = a.number_or("--beta", 0.99, 0, 1);
  check_output("-o", *o, {*w});
  const auto ticks = a.value("--ticks");
  const std::optional<std::string> tau_given = a.value("--presence-tau");
  const double tau_v = a.number_or("--presence-tau", 0, 0, 60);
  if (ticks) check_output("--ticks", *ticks, {*w, *o});
  const std::filesystem::path val = std::filesystem::path(*data) / "val";
  const std::string dir = std::filesystem::is_directory(val) ? val.string() : *data;
  const std::vector<std::string> recs = camera::sim::list_recordings(dir);
  err << "calibrating presence on " << recs.size() << " recordings in " << dir << " (" << seconds << " s each, the first "
      << skip << " s left out)\n";
  weights::Weights wt = weights::load_weights(*w);
  const ModelConfig before = parse_model_config(wt.config_json, *w);
  run::RunOptions opt;
  opt.rate_hz = rate;
  if (beta) opt.beta = beta_v;
  const double tau = tau_given ? tau_v : before.presence_tau_s;
  opt.presence_tau_s = tau;
  const bool depth_tau_given = a.value("--depth-tau").has_value();
  if (depth_tau_given) opt.depth_tau_s = a.number_or("--depth-tau", 0, 0, 60);
  if (a.flag("--depth-without-forearms")) opt.depth_forearms = false;
  vet_recordings_up_front(recs, err);
  // Stage 1's cut first: presence is fitted on the share of the frame the cut mask covers.
  std::optional<double> cut;
  if (a.flag("--choose-mask-cut")) {
    const std::vector<double> cuts = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8};
    err << "choosing stage 1's cut on the recordings with a dancer (stage 1 on every tick, its mask against the true mask):\n";
    out << std::defaultfloat << std::setprecision(3) << "mask cut sweep (IoU, stage 1 on every tick):";
    const std::vector<double> ious = run::sweep_mask_cuts(*w, recs, cuts, rate, seconds, skip, err);
    double best = -1;
    for (std::size_t k = 0; k < cuts.size(); ++k) {
      out << "  " << cuts[k] << ": " << ious[k];
      if (ious[k] > best) best = ious[k], cut = cuts[k];
    }
    out << "\nchosen: run.mask_cut " << *cut << " (was " << before.mask_cut << ")\n";
    opt.mask_cut = cut;
    std::ostringstream cj;
    cj << std::setprecision(9) << *cut;
    wt.config_json = with_run_setting(wt.config_json, "mask_cut", cj.str());
  }
  std::vector<std::pair<double, double>> depths;
  auto samples = run::presence_samples(*w, recs, opt, seconds + skip, skip, err, &depths);
  out << "before (" << (before.presence_calibrated ? "its calibration" : "the uncalibrated default") << ", a "
      << before.presence_a << ", b " << before.presence_b << ", tau_s " << before.presence_tau_s << "):\n";
  run::print_presence_report(run::presence_report(samples, before.presence_a, before.presence_b, 0.5, before.presence_tau_s), out);
  // The look-again rule reads the calibration (a stored mask that says nobody is not reused),
  // so the ticks run under a fit differ from those it was fitted on: run again under the fit
  // until a refit would move P(person) by less than 0.02 (at most 4 more runs, halfway steps
  // after the first). What is stored is the calibration the last run ran under, and its
  // report is that run's.
  const auto settled = run::settle_presence(
      {before.presence_a, before.presence_b}, run::fit_presence(samples, tau),
      [&](const std::array<double, 2>& ab) {
        opt.presence_ab = ab;
        err << std::defaultfloat << std::setprecision(6) << "running again under a " << ab[0] << ", b " << ab[1] << "\n";
        depths.clear();
        samples = run::presence_samples(*w, recs, opt, seconds + skip, skip, err, &depths);
        return run::fit_presence(samples, tau);
      },
      0.02, 4);
  const std::array<double, 2> used = settled.used;
  out << std::defaultfloat << std::setprecision(6) << "fitted: a " << used[0] << ", b " << used[1] << ", tau_s " << tau
      << " (balanced log-loss " << run::presence_log_loss(samples, used[0], used[1], tau)
      << "; refitting on its own ticks would move P(person) by " << std::setprecision(2) << settled.moved << " at most):\n";
  run::print_presence_report(run::presence_report(samples, used[0], used[1], 0.5, tau), out);
  print_smoothing_sweep(samples, tau, out);
  if (ticks) {
    run::write_presence_ticks(*ticks, samples);
    out << "wrote " << *ticks << " (" << samples.size() << " ticks of that run)\n";
  }
  std::ostringstream pj;
  pj << std::setprecision(9) << "{\"a\": " << used[0] << ", \"b\": " << used[1] << ", \"tau_s\": " << tau << "}";
  wt.config_json = with_run_setting(wt.config_json, "presence", pj.str());
  // The deployed depth: the body-height prior times a scale, fitted on the same poses.
  if (!depths.empty()) {
    const double r = run::fit_depth_scale(depths);
    double before_mm = 0, after_mm = 0;
    for (const auto& [truth, est] : depths) {
      before_mm += std::abs(est - truth);
      after_mm += std::abs(r * est - truth);
    }
    const double scale = before.depth_scale * r;
    out << std::defaultfloat << std::setprecision(4) << "head depth (" << depths.size()
        << " poses with a dancer): median truth / estimate " << r << "; run.depth_scale " << before.depth_scale << " -> "
        << scale << std::fixed << std::setprecision(0) << ", mean |error| " << before_mm / double(depths.size()) << " -> "
        << after_mm / double(depths.size()) << " mm\n";
    std::ostringstream dj;
    dj << std::setprecision(9) << scale;
    wt.config_json = with_run_setting(wt.config_json, "depth_scale", dj.str());
  }
  if (opt.depth_forearms) wt.config_json = with_run_setting(wt.config_json, "depth_forearms", "false");
  if (depth_tau_given) {
    std::ostringstream tj;
    tj << std::setprecision(9) << *opt.depth_tau_s;
    wt.config_json = with_run_setting(wt.config_json, "depth_tau_s", tj.str());
  }
  std::optional<double> chosen;
  if (beta) chosen = beta_v;
  if (a.flag("--choose-beta")) {
    if (beta) throw UsageError("weights calibrate: --beta and --choose-beta exclude each other");
    const double tol = a.number_or("--beta-tolerance", 0.02, 0, 1);
    const std::vector<double> betas = {0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95, 0.99, 1.01};
    err << "choosing beta on the recordings with a dancer (mask in use against the true mask):\n";
    const auto points = run::sweep_beta(*w, recs, betas, rate, seconds, skip, err, cut);
    const run::BetaPoint pick = run::choose_beta(points, tol);
    out << std::defaultfloat << std::setprecision(3) << "beta sweep (stage 1 share of ticks, mask IoU):";
    for (const auto& p : points) out << "  " << p.beta << ": " << p.stage1_share << ", " << p.iou;
    for (const auto& p : points)
      if (p.beta > 1 && p.scored_masks)
        out << "\nthe mask scores against their true quality (1 - mean |mask error|), stage 1 on every tick, "
            << p.scored_masks << " masks: correlation " << p.score_quality_correlation << ", mean |score - quality| "
            << p.score_quality_mae;
    out << "\nchosen: beta " << pick.beta << ", stage 1 on " << 100 * pick.stage1_share << "% of the ticks, IoU " << pick.iou
        << " (within " << tol << " of the best)\n";
    chosen = pick.beta;
  }
  if (chosen) {
    std::ostringstream bj;
    bj << std::setprecision(9) << *chosen;
    wt.config_json = with_run_setting(wt.config_json, "beta", bj.str());
  }
  weights::save_weights(*o, wt);
  out << "wrote " << *o << " (config run.presence" << (depths.empty() ? "" : ", run.depth_scale")
      << (chosen ? ", run.beta" : "") << (cut ? ", run.mask_cut" : "") << (depth_tau_given ? ", run.depth_tau_s" : "") << (opt.depth_forearms ? ", run.depth_forearms" : "") << ")\n";
  return kOk;
}

}  // namespace

int cmd_weights(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  if (argv.empty()) throw UsageError("weights needs a subcommand: inspect, diff or verify (see 'yelan weights --help')");
  const std::string sub = argv[0];
  const std::vector<std::string> rest(argv.begin() + 1, argv.end());
  try {
    if (sub == "inspect") return inspect(Args("weights inspect", rest, {}, {"--json"}), out);
    if (sub == "diff") return diff(Args("weights diff", rest, {"--tol"}, {"--all"}), out);
    if (sub == "verify") return verify(Args("weights verify", rest, {"--config"}, {}), out, err);
    if (sub == "init") return weights_init(rest, out);
    if (sub == "calibrate")
      return calibrate(Args("weights calibrate", rest, {"--weights", "--data", "-o", "--seconds", "--skip", "--rate", "--beta", "--beta-tolerance", "--ticks",
                                                          "--presence-tau", "--depth-tau"},
                            {"--choose-beta", "--choose-mask-cut", "--depth-without-forearms"}),
                       out, err);
    if (sub == "combine") return combine(Args("weights combine", rest, {"--mask", "--pose", "-o", "--config"}, {}), out);
    if (sub == "widen") return widen(Args("weights widen", rest, {"--weights", "--config", "-o", "--seed"}, {}), out);
    if (sub == "narrow") return narrow(Args("weights narrow", rest, {"--weights", "--config", "-o"}, {}), out);
  } catch (const weights::WeightsError& e) {
    std::istringstream lines(e.what());
    for (std::string line; std::getline(lines, line);) err << "yelan: error: " << printable(line) << "\n";
    return kUsageError;
  } catch (const weights::JsonError& e) {
    err << "yelan: error: config JSON: " << printable(e.what()) << "\n";
    return kUsageError;
  }
  throw UsageError("unknown weights subcommand '" + sub + "' (inspect, diff, verify, init, combine, calibrate, widen, narrow)");
}

}  // namespace yelan::cli
