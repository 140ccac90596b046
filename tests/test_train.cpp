// The trainer and the metrics: normalisation round trip, hand-computed MPJPE/PCK/AUC, a
// short training run through the CLI, and --resume giving the uninterrupted loss curve.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "engine/train/metrics.h"
#include "engine/train/pose_norm.h"
#include "weights_tools/weights_file.h"

using namespace yelan::train;

TEST_CASE("train: joint normalisation round-trips and matches the formula by hand", "[train]") {
  const Intrinsics k{485, 485, 173, 130, 346, 260};
  const std::array<double, 3> head{100, -500, 3500};
  const auto n = normalise_joint(head, k, 3500);
  // u = 485*100/3500 + 173 = 186.857; x_n = (u - 173)/173
  CHECK(n[0] == Approx((485.0 * 100 / 3500 + 173 - 173) / 173));
  CHECK(n[1] == Approx((485.0 * -500 / 3500 + 130 - 130) / 130));
  CHECK(n[2] == Approx(0).margin(1e-12));  // Z = z_ref
  const std::array<double, 3> hand{-300, 200, 3800};
  const auto m = normalise_joint(hand, k, 3500);
  const double s = 3500 * std::max(346 / 485.0, 260 / 485.0), r = std::sqrt(3500.0 * 3500 + s * s);
  CHECK(m[2] == Approx((r + 3500) / s * (1 - 3500 / 3800.0)));
  const auto back = denormalise_joint(m, k, 3500);
  for (int i = 0; i < 3; ++i) CHECK(back[i] == Approx(hand[i]).margin(1e-9));
}

TEST_CASE("train: MPJPE, PCK@150 and AUC by hand, paper protocol and root-aligned", "[train]") {
  Pose13 truth{}, pred{};
  for (int j = 0; j < kJoints; ++j) truth[j] = {double(j) * 10, 0, 3000};
  pred = truth;
  pred[0][0] += 100;  // head 100 mm off
  pred[1][1] += 200;  // shoulder 200 mm off
  std::array<std::uint8_t, kJoints> valid;
  valid.fill(1);
  valid[12] = 0;
  PoseMetrics m;
  m.add(pred, truth, valid);
  const PoseScores s = m.scores();
  CHECK(s.joints == 12);
  CHECK(s.frames == 1);
  CHECK(s.mpjpe_mm == Approx(300.0 / 12));
  CHECK(s.pck150 == Approx(11.0 / 12));
  // AUC: thresholds 0, 17.24, ..., 500: 10 joints at 0 count everywhere; the 100 mm one from
  // threshold 6 (103.4) on (24 of 30), the 200 mm one from threshold 12 (206.9) on (18 of 30).
  CHECK(s.auc == Approx((10 * 30 + 24 + 18) / (12.0 * 30)));
  CHECK(s.mpjpe_per_joint[0] == Approx(100));
  // A pose shifted as a whole is perfect after root alignment.
  Pose13 shifted = truth;
  for (auto& p : shifted) p[2] += 250;
  PoseMetrics r;
  r.add(shifted, truth, valid);
  CHECK(r.scores().mpjpe_mm == Approx(250));
  CHECK(r.scores().mpjpe_root_mm == Approx(0).margin(1e-9));
  CHECK(r.scores().pck150 == 0);
  CHECK(r.scores().pck150_root == 1);
}

TEST_CASE("train: the error split puts an image-plane miss in pixels and a depth miss in mm", "[train]") {
  Pose13 truth{}, pred{};
  for (int j = 0; j < kJoints; ++j) truth[j] = {double(j) * 10, -50, 3000};
  pred = truth;
  pred[0][0] += 30;   // head: 30 mm sideways at 3 m, fx 300 -> 3 px, no depth error
  pred[1][2] += 400;  // shoulder: 400 mm deeper, along its own ray: same pixel
  for (int c = 0; c < 3; ++c) pred[1][std::size_t(c)] = truth[1][std::size_t(c)] * 3400 / 3000;
  std::array<std::uint8_t, kJoints> valid;
  valid.fill(1);
  valid[12] = 0;
  ErrorSplit e;
  e.add(pred, truth, valid, Intrinsics{300, 300, 173, 130, 346, 260});
  const ErrorSplitScores s = e.scores();
  CHECK(s.image_px[0] == Approx(3.0));
  CHECK(s.depth_mm[0] == Approx(0).margin(1e-9));
  CHECK(s.image_px[1] == Approx(0).margin(1e-9));
  CHECK(s.depth_mm[1] == Approx(400));
  CHECK(s.n[12] == 0);  // never valid: n/a, not 0
  CHECK(s.mean_image_px == Approx(3.0 / 12));
  CHECK(s.mean_depth_mm == Approx(400.0 / 12));
  CHECK(s.depth_bias_mm[1] == Approx(400));
  // The hips are where they should be: hip alignment leaves the shoulder's 400 mm.
  CHECK(s.depth_root_mm[1] == Approx(400));
  CHECK(s.n_root[12] == 0);
  // The whole body 200 mm too near: every joint's depth is off, none after hip alignment.
  Pose13 near = truth;
  for (auto& p : near)
    for (double& c : p) c *= 2800.0 / 3000.0;
  ErrorSplit whole;
  whole.add(near, truth, valid, Intrinsics{300, 300, 173, 130, 346, 260});
  const ErrorSplitScores w = whole.scores();
  CHECK(w.mean_depth_mm == Approx(200));
  CHECK(w.depth_bias_mm[3] == Approx(-200));
  CHECK(w.mean_depth_root_mm == Approx(0).margin(1e-9));
  CHECK(w.mean_image_px == Approx(0).margin(1e-9));
  valid[5] = 0;  // no hip centre: no hip-aligned depth
  ErrorSplit no_hips;
  no_hips.add(near, truth, valid, Intrinsics{300, 300, 173, 130, 346, 260});
  CHECK(no_hips.scores().n_root[3] == 0);
  CHECK(no_hips.scores().n[3] == 1);
}

TEST_CASE("train: a short run writes its log and checkpoints, and --resume continues bit-exactly", "[train][cli]") {
  yelan::test::CliTempDir d("train");
  const std::vector<std::string> base = {"train", "--stage", "pose", "--config", "micro", "--sim",
                                         "ben-dance3-front-high-static,lena-dance4-left-medium-dynamic",
                                         "--epoch-steps", "2", "--val-windows", "1", "--occlusion", "--batch", "1"};
  auto run = [&](const std::string& out, const std::string& steps, std::vector<std::string> extra = {}) {
    auto v = base;
    v.insert(v.end(), {"-o", d / out, "--steps", steps});
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  const auto whole = run("a", "4", {"--threads", "1"});
  INFO(whole.err);
  REQUIRE(whole.code == 0);
  REQUIRE(run("b", "4", {"--threads", "2", "--stop-at", "2"}).code == 0);
  std::ofstream(d / "b/log.csv", std::ios::app) << "3,1,0.12";  // a row cut short by a crash
  const auto resumed = run("b", "4", {"--resume", "--threads", "2"});
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  CHECK(yelan::test::contains(resumed.err, "resuming"));
  auto losses = [&](const std::string& dir) {
    std::istringstream in(yelan::test::slurp(d / (dir + "/log.csv")));
    std::vector<std::string> cols;
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::istringstream l(line);
      std::string step, epoch, loss, val;
      std::getline(l, step, ','), std::getline(l, epoch, ','), std::getline(l, loss, ','), std::getline(l, val, ',');
      cols.push_back(step + " " + loss + " " + val);
    }
    return cols;
  };
  const auto la = losses("a"), lb = losses("b");
  REQUIRE(la.size() == 4);
  CHECK(la == lb);
  for (const char* f : {"checkpoint.h5", "checkpoint.state", "best.h5", "final.h5"})
    CHECK(std::filesystem::exists(d / (std::string("a/") + f)));
  CHECK(yelan::test::slurp(d / "a/final.h5") == yelan::test::slurp(d / "b/final.h5"));
  // Stages trained apart combine into one model file.
  const auto comb = yelan::test::run_cli({"weights", "combine", "--mask", d / "b/final.h5", "--pose", d / "a/final.h5", "-o",
                                          d / "both.h5"});
  INFO(comb.err);
  CHECK(comb.code == 0);
  CHECK(yelan::test::run_cli({"weights", "combine", "--mask", d / "b/final.h5", "-o", d / "x.h5"}).code == 2);
  // --config swaps in inference settings; a config the tensors do not fit is refused.
  std::string micro = yelan::test::slurp(std::string(YELAN_SOURCE_DIR) + "/weights_tools/configs/micro.json");
  std::string crop = micro, wider = micro;
  crop.replace(crop.find("\"convlstm\""), 10, "\"crop_margin\": 4, \"convlstm\"");
  wider.replace(wider.find("\"hidden\": 8"), 11, "\"hidden\": 9");
  std::ofstream(d / "crop.json") << crop;
  std::ofstream(d / "wider.json") << wider;
  const auto cc = yelan::test::run_cli({"weights", "combine", "--mask", d / "both.h5", "--pose", d / "both.h5", "--config",
                                        d / "crop.json", "-o", d / "crop.h5"});
  INFO(cc.err);
  CHECK(cc.code == 0);
  CHECK(yelan::test::contains(yelan::test::run_cli({"weights", "inspect", d / "crop.h5"}).out, "crop_margin"));
  const auto cw = yelan::test::run_cli({"weights", "combine", "--mask", d / "both.h5", "--pose", d / "both.h5", "--config",
                                        d / "wider.json", "-o", d / "wider.h5"});
  CHECK(cw.code == 2);
  CHECK(yelan::test::contains(cw.err, "do not fit"));
  std::string fine = micro;
  fine.replace(fine.find("\"convlstm\""), 10, "\"head_stride\": 4, \"convlstm\"");
  std::ofstream(d / "fine.json") << fine;
  const auto cs = yelan::test::run_cli({"weights", "combine", "--mask", d / "both.h5", "--pose", d / "both.h5", "--config",
                                        d / "fine.json", "-o", d / "fine.h5"});
  CHECK(cs.code == 2);
  CHECK(yelan::test::contains(cs.err, "pose.head_stride"));
  CHECK_FALSE(std::filesystem::exists(d / "wider.h5"));
  // The trained weights evaluate on held-out test scenes; the JSON has the contract's keys.
  const auto ev = yelan::test::run_cli({"eval", "--weights", d / "a/final.h5", "--sim", "test", "--scenes", "2", "--seconds",
                                        "0.04", "--seed", "3", "--history", "0.1", "--json", d / "eval.json"});
  INFO(ev.err);
  REQUIRE(ev.code == 0);
  CHECK(yelan::test::contains(ev.out, "MPJPE"));
  const std::string js = yelan::test::slurp(d / "eval.json");
  for (const char* key : {"\"mpjpe_mm\"", "\"pck150\"", "\"auc\"", "\"mpjpe_root_mm\"", "\"frames\": 4", "\"by_condition\"",
                          "\"lighting\"", "\"mask_iou\"", "\"floors\"", "\"constant\"", "\"mean_pose_at_hip\"",
                          "\"per_view_mean_pose_at_hip\"", "\"swap_share_by_view\"", "\"mask_iou_by_condition\"",
                          "\"error_split\"", "\"mean_image_px\"", "\"mean_depth_root_mm\"", "\"depth_bias_mm\"",
                          "\"depth_root_mm\"", "\"scene\""})
    CHECK(yelan::test::contains(js, key));
  CHECK(yelan::test::contains(ev.out, ", IoU "));  // the mask IoU of each condition beside its MPJPE
  // A config without stage 1 has no mask IoU to report: n/a, not 0.
  std::string nomask = micro;
  nomask.replace(nomask.find("\"convlstm\""), 10, "\"masked_input\": false, \"convlstm\"");
  std::ofstream(d / "nomask.json") << nomask;
  REQUIRE(yelan::test::run_cli({"weights", "combine", "--mask", d / "both.h5", "--pose", d / "both.h5", "--config",
                                d / "nomask.json", "-o", d / "nomask.h5"}).code == 0);
  const auto evn = yelan::test::run_cli({"eval", "--weights", d / "nomask.h5", "--sim", "test", "--scenes", "1", "--seconds",
                                         "0.04", "--seed", "3", "--history", "0.1", "--json", d / "evaln.json"});
  INFO(evn.err);
  REQUIRE(evn.code == 0);
  CHECK(yelan::test::contains(evn.out, "mask IoU n/a"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "evaln.json"), "\"mask_iou\": null"));
  // Weights and state from different steps (a stop between the two writes) are refused.
  std::filesystem::copy_file(d / "crop.h5", d / "b/checkpoint.h5", std::filesystem::copy_options::overwrite_existing);
  const auto mixed = run("b", "6", {"--resume"});
  CHECK(mixed.code != 0);
  CHECK(yelan::test::contains(mixed.err, "does not belong to"));
  // Nothing to resume from, a bad stage, a missing option: clear errors.
  CHECK(run("none", "2", {"--resume"}).code != 0);
  CHECK(yelan::test::run_cli({"train", "--stage", "legs", "--config", "micro", "--sim", "train", "-o", d / "x"}).code == 2);
  CHECK(yelan::test::run_cli({"train", "--config", "micro"}).code == 2);
  const auto bad_cfg = yelan::test::run_cli({"train", "--stage", "mask", "--config", "no-such-config", "--sim", "train", "-o", d / "x"});
  CHECK(bad_cfg.code == 2);
  CHECK(yelan::test::contains(bad_cfg.err, "no-such-config"));
}

TEST_CASE("train: --init starts from a checkpoint, which holds only its trained group, unless the run trains the other", "[train][cli]") {
  yelan::test::CliTempDir d("train-init");
  std::string nomask = yelan::test::slurp(std::string(YELAN_SOURCE_DIR) + "/weights_tools/configs/micro.json");
  nomask.replace(nomask.find("\"convlstm\""), 10, "\"masked_input\": false, \"convlstm\"");
  std::ofstream(d / "nomask.json") << nomask;
  auto run = [&](const std::string& cfg, const std::string& out, std::vector<std::string> extra = {}) {
    std::vector<std::string> v = {"train", "--stage", "pose", "--config", cfg, "--sim", "ben-dance3-front-high-static",
                                  "--steps", "2", "--epoch-steps", "2", "--val-windows", "1", "--batch", "1", "--threads", "1",
                                  "-o", d / out};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  REQUIRE(run(d / "nomask.json", "a").code == 0);
  const auto fresh = run(d / "nomask.json", "fresh");
  const auto from = run(d / "nomask.json", "from", {"--init", d / "a/checkpoint.h5"});
  INFO(from.err);
  REQUIRE(from.code == 0);
  auto first_loss = [&](const std::string& dir) {
    std::istringstream in(yelan::test::slurp(d / (dir + "/log.csv")));
    std::string line;
    std::getline(in, line);
    std::getline(in, line);
    return line.substr(0, line.find(',', line.find(',', line.find(',') + 1) + 1));
  };
  CHECK(first_loss("a") == first_loss("fresh"));  // the same draw from the same seed
  CHECK(first_loss("from") != first_loss("fresh"));  // the checkpoint's weights, not the seed's
  // A masked pose stage learns behind the true masks: it starts from the checkpoint too, and
  // says its files' mask group is untrained.
  const auto masked = run("micro", "masked", {"--init", d / "a/checkpoint.h5"});
  INFO(masked.err);
  CHECK(masked.code == 0);
  CHECK(yelan::test::contains(masked.err, "mask group of the files written here is untrained"));
  // The mask stage trains the mask net, which a pose checkpoint does not hold.
  const auto mask_stage = yelan::test::run_cli({"train", "--stage", "mask", "--config", "micro", "--sim",
                                                "ben-dance3-front-high-static", "--steps", "1", "--val-windows", "1",
                                                "--batch", "1", "--threads", "1", "--init", d / "a/checkpoint.h5", "-o",
                                                d / "mask"});
  CHECK(mask_stage.code != 0);
  CHECK(yelan::test::contains(mask_stage.err, "/mask"));
}

TEST_CASE("train: --steps fewer than --epoch-steps still validates at the end and writes best.h5", "[train][cli]") {
  // Issue 17 row 14: the run ended before its first epoch, so it reported "best validation 1e+30"
  // (the initial value) and wrote no best.h5.
  yelan::test::CliTempDir d("train-short");
  const auto r = yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                       "--steps", "2", "--epoch-steps", "100", "--val-windows", "1", "--batch", "1",
                                       "--threads", "1", "-o", d / "run"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(std::filesystem::exists(d / "run/best.h5"));
  CHECK(yelan::test::contains(r.out, "best validation"));
  CHECK_FALSE(yelan::test::contains(r.out + r.err, "1e+30"));
  CHECK_FALSE(yelan::test::contains(r.out + r.err, "1e30"));
}

TEST_CASE("train: the mask stage logs its validation mask IoU, and an older log gains the column on resume", "[train][cli]") {
  yelan::test::CliTempDir d("train-mask-iou");
  auto run = [&](const std::string& steps, std::vector<std::string> extra = {}) {
    std::vector<std::string> v = {"train", "--stage", "mask", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                  "--epoch-steps", "1", "--val-windows", "1", "--batch", "1", "--threads", "1",
                                  "-o", d / "m", "--steps", steps};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  auto rows = [&] {
    std::istringstream in(yelan::test::slurp(d / "m/log.csv"));
    std::vector<std::vector<std::string>> out;
    for (std::string line; std::getline(in, line);) {
      std::vector<std::string> cols;
      std::istringstream l(line);
      for (std::string c; std::getline(l, c, ',');) cols.push_back(c);
      out.push_back(cols);
    }
    return out;
  };
  const auto first = run("2", {"--stop-at", "1"});
  INFO(first.err);
  REQUIRE(first.code == 0);
  CHECK(yelan::test::contains(first.err, "validation mask IoU "));
  CHECK(yelan::test::contains(first.err, " (at sigmoid > 0.1; 0.3: "));
  auto r = rows();
  REQUIRE(r.size() == 2);
  REQUIRE(r[0].size() == 11);
  CHECK(r[0][10] == "val_mask_iou");
  const double iou = std::stod(r[1][10]);
  CHECK(iou >= 0);
  CHECK(iou <= 1);
  // The log as an older trainer wrote it: no last column.
  std::ofstream(d / "m/log.csv") << "step,epoch,loss,val_loss,lr,grad_norm,samples_per_s,wall_s,val_mpjpe_mm,cpu_s\n"
                                 << r[1][0] << ",0,0.5,0.5,0.001,1,1,1,-1,1\n";
  const auto resumed = run("2", {"--resume"});
  INFO(resumed.err);
  REQUIRE(resumed.code == 0);
  r = rows();
  REQUIRE(r.size() == 3);
  CHECK(r[0][10] == "val_mask_iou");
  REQUIRE(r[1].size() == 11);
  CHECK(r[1][10] == "-1");
  REQUIRE(r[2].size() == 11);
  CHECK(std::stod(r[2][10]) >= 0);
}

TEST_CASE("train: --mask-frames sets the mask stage's training windows, validation keeps the config's", "[train][cli]") {
  yelan::test::CliTempDir d("train-mask-frames");
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> v = {"train", "--stage", "mask", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                  "--epoch-steps", "2", "--val-windows", "1", "--batch", "2", "--threads", "1",
                                  "-o", d / out, "--steps", "2"};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  auto losses = [&](const std::string& out) {
    std::istringstream in(yelan::test::slurp(d / (out + "/log.csv")));
    std::string line, all;
    std::getline(in, line);
    for (; std::getline(in, line);) {
      std::vector<std::string> c;
      std::istringstream l(line);
      for (std::string x; std::getline(l, x, ',');) c.push_back(x);
      REQUIRE(c.size() == 11);
      all += c[2] + " " + c[3] + " " + c[10] + "\n";  // loss, validation loss, IoU
    }
    return all;
  };
  const auto plain = run("plain", {});
  REQUIRE(plain.code == 0);
  // The config's own window (micro: 2) is the run without the flag, value for value.
  const auto same = run("same", {"--mask-frames", "2"});
  INFO(same.err);
  REQUIRE(same.code == 0);
  CHECK_FALSE(yelan::test::contains(same.err, "training windows of"));
  CHECK(losses("same") == losses("plain"));
  const auto one = run("one", {"--mask-frames", "1"});
  INFO(one.err);
  REQUIRE(one.code == 0);
  CHECK(yelan::test::contains(one.err, "training windows of 1 frame (--mask-frames); validation windows of the config's 2"));
  CHECK(losses("one") != losses("plain"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "one/run.json"), "\"window\": 1,"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "plain/run.json"), "\"window\": 2,"));
  // The pose net's ConvLSTM needs the config's window.
  const auto pose = yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                          "-o", d / "p", "--steps", "1", "--mask-frames", "1"});
  CHECK(pose.code == 2);
  CHECK(yelan::test::contains(pose.err, "--mask-frames"));
  const auto zero = run("zero", {"--mask-frames", "0"});
  CHECK(zero.code == 2);
}

TEST_CASE("train: --dice-weight and --mask-focus change the mask stage's training loss, not its validation loss's formula", "[train][cli]") {
  yelan::test::CliTempDir d("train-dice");
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> v = {"train", "--stage", "mask", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                  "--epoch-steps", "1", "--val-windows", "1", "--batch", "2", "--threads", "1",
                                  "-o", d / out, "--steps", "1"};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  auto row = [&](const std::string& out) {  // the first step's loss and validation loss
    std::istringstream in(yelan::test::slurp(d / (out + "/log.csv")));
    std::string line;
    std::getline(in, line);
    std::getline(in, line);
    std::vector<std::string> c;
    std::istringstream l(line);
    for (std::string x; std::getline(l, x, ',');) c.push_back(x);
    REQUIRE(c.size() == 11);
    return std::make_pair(std::stod(c[2]), std::stod(c[3]));
  };
  const auto plain = run("plain", {}), dice = run("dice", {"--dice-weight", "2"});
  INFO(dice.err);
  REQUIRE(plain.code == 0);
  REQUIRE(dice.code == 0);
  // One step from the same start on the same window: the training loss gains 2 x Dice (> 0
  // for a net that has not learned), the validation loss is scored after the step, without it.
  CHECK(row("dice").first > row("plain").first + 0.5);
  CHECK(row("dice").second < row("plain").first + 0.5);
  CHECK(yelan::test::contains(yelan::test::slurp(d / "dice/run.json"), "\"dice_weight\": 2"));
  const auto pose = yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                          "-o", d / "p", "--steps", "1", "--dice-weight", "1"});
  CHECK(pose.code == 2);
  CHECK(yelan::test::contains(pose.err, "--dice-weight"));
  CHECK(run("neg", {"--dice-weight", "-1"}).code == 2);
  // --mask-focus 2: masks 1 and 2 weigh as the current one, about 2 x ln 2 more for a net
  // that has not learned; recorded, and a resume must keep it.
  const auto focus = run("focus", {"--mask-focus", "2"});
  INFO(focus.err);
  REQUIRE(focus.code == 0);
  CHECK(row("focus").first > row("plain").first + 0.5);
  CHECK(yelan::test::contains(yelan::test::slurp(d / "focus/run.json"), "\"mask_focus\": 2"));
  const auto resumed = run("focus", {"--resume"});
  CHECK(resumed.code == 2);
  CHECK(yelan::test::contains(resumed.err, "--mask-focus 2"));
  CHECK(run("far", {"--mask-focus", "99"}).code == 2);
  const auto pose_focus = yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                                "-o", d / "pf", "--steps", "1", "--mask-focus", "1"});
  CHECK(pose_focus.code == 2);
  CHECK(yelan::test::contains(pose_focus.err, "--mask-focus"));
}

TEST_CASE("train: --data DIR trains on recordings split by recording, resumes bit-exactly, and eval --data scores them", "[train][cli]") {
  yelan::test::CliTempDir d("train-data");
  std::filesystem::create_directories(d / "rec");
  for (const char* p : {"ben-dance3-front-high-static", "ana-05_04-left-medium-dynamic-occluded"})
    REQUIRE(yelan::test::run_cli({"sim", "--preset", p, "--duration", "0.4s", "-o", d / (std::string("rec/") + p + ".yelan.h5")})
                .code == 0);
  auto run = [&](const std::string& out, const std::string& steps, std::vector<std::string> extra = {}) {
    std::vector<std::string> v = {"train", "--stage", "pose", "--config", "micro", "--data", d / "rec", "--epoch-steps", "2",
                                  "--val-windows", "1", "--batch", "2", "-o", d / out, "--steps", steps};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  const auto whole = run("a", "4");
  INFO(whole.err);
  REQUIRE(whole.code == 0);
  CHECK(yelan::test::contains(whole.err, "1 recordings for training, 1 for validation"));
  REQUIRE(run("b", "4", {"--stop-at", "2"}).code == 0);
  REQUIRE(run("b", "4", {"--resume"}).code == 0);
  CHECK(yelan::test::slurp(d / "a/final.h5") == yelan::test::slurp(d / "b/final.h5"));
  const auto ev = yelan::test::run_cli({"eval", "--weights", d / "a/final.h5", "--data", d / "rec", "--seconds", "0.2",
                                        "--json", d / "eval.json"});
  INFO(ev.err);
  REQUIRE(ev.code == 0);
  const std::string js = yelan::test::slurp(d / "eval.json");
  for (const char* key : {"\"mpjpe_mm\"", "\"frames\": 20", "\"occluded\"", "\"left\"", "\"scenes\": 2"})
    CHECK(yelan::test::contains(js, key));
  // --poses: every scored frame, the prediction and the label; their errors are eval's MPJPE.
  const auto kept = yelan::test::run_cli({"eval", "--weights", d / "a/final.h5", "--data", d / "rec", "--seconds", "0.2",
                                          "--no-floors", "--poses", d / "frames.csv"});
  INFO(kept.err);
  REQUIRE(kept.code == 0);
  std::istringstream csv(yelan::test::slurp(d / "frames.csv"));
  std::string line;
  std::getline(csv, line);
  {
    std::vector<std::string> head;
    std::istringstream l(line);
    for (std::string f; std::getline(l, f, ',');) head.push_back(f);
    REQUIRE(head.size() == 10 + 2 * 39 + 13 + 2);
    CHECK(line.rfind("source,view,window,frame,t_us,fx,fy,cx,cy,true_head_depth_mm,j0_x,", 0) == 0);
    CHECK(head[49] == "true_j0_x");  // the prediction first, then the label
    CHECK(head[88] == "valid0");
    CHECK(head[102] == "height");
  }
  double sum = 0;
  int rows = 0, joints = 0;
  std::set<std::string> sources;
  while (std::getline(csv, line)) {
    std::vector<std::string> c;
    std::istringstream l(line);
    for (std::string f; std::getline(l, f, ',');) c.push_back(f);
    REQUIRE(c.size() == 10 + 2 * 39 + 13 + 2);
    CHECK(c[101] == "346");
    CHECK(c[102] == "260");
    ++rows;
    sources.insert(c[0] + "/" + c[1]);
    CHECK(std::stod(c[5]) > 100);  // fx
    for (int j = 0; j < 13; ++j) {
      if (c[10 + 78 + j] != "1") continue;
      double e = 0;
      for (int a = 0; a < 3; ++a) e += std::pow(std::stod(c[10 + 3 * j + a]) - std::stod(c[10 + 39 + 3 * j + a]), 2);
      sum += std::sqrt(e);
      ++joints;
    }
  }
  CHECK(rows == 20);
  CHECK(sources == std::set<std::string>{"ben-dance3-front-high-static/front", "ana-05_04-left-medium-dynamic-occluded/left"});
  REQUIRE(joints > 0);
  CHECK(sum / joints == Approx(nlohmann::json::parse(js)["mpjpe_mm"].get<double>()).epsilon(1e-4));
  // With --run, --poses keeps the deployed path's own layout.
  const auto deployed = yelan::test::run_cli({"eval", "--run", "--weights", d / "a/final.h5", "--data", d / "rec",
                                              "--seconds", "0.3", "--skip", "0", "--poses", d / "run.csv"});
  INFO(deployed.err);
  REQUIRE(deployed.code == 0);
  CHECK(yelan::test::slurp(d / "run.csv").rfind("source,t_us,dancer,person,confidence,mask_ran,", 0) == 0);
  // Pictures of stage 1 against the truth, one per recording; not where stage 1 does not run.
  const auto pics = yelan::test::run_cli({"eval", "--weights", d / "a/final.h5", "--data", d / "rec", "--seconds", "0.2",
                                          "--no-floors", "--mask-pictures", d / "pics"});
  INFO(pics.err);
  REQUIRE(pics.code == 0);
  CHECK(yelan::test::contains(pics.out, "wrote 2 pictures of stage 1 against the truth"));
  for (const char* p : {"ben-dance3-front-high-static", "ana-05_04-left-medium-dynamic-occluded"})
    CHECK(yelan::test::slurp(d / (std::string("pics/") + p + ".png")).substr(1, 3) == "PNG");
  const auto no_pics = yelan::test::run_cli({"eval", "--weights", d / "a/final.h5", "--data", d / "rec", "--true-mask",
                                             "--mask-pictures", d / "pics2"});
  CHECK(no_pics.code == 2);
  CHECK(yelan::test::contains(no_pics.err, "--mask-pictures"));
  // Both sources, or a folder without recordings: usage errors naming the problem.
  CHECK(yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--data", d / "rec", "--sim", "train", "-o",
                              d / "x"}).code == 2);
  std::filesystem::create_directories(d / "empty");
  const auto none = yelan::test::run_cli({"eval", "--weights", d / "a/final.h5", "--data", d / "empty"});
  CHECK(none.code == 2);
  CHECK(yelan::test::contains(none.err, "no recordings"));
}

namespace {

// A dataset folder (train/, val/) holding one dancer recording of `duration` in each split.
void one_recording_dataset(const std::string& dir, const std::string& duration) {
  std::filesystem::create_directories(dir + "/train");
  std::filesystem::create_directories(dir + "/val");
  REQUIRE(yelan::test::run_cli({"sim", "--preset", "ben-dance3-front-high-static", "--duration", duration, "-o",
                                dir + "/train/t.yelan.h5"}).code == 0);
  std::filesystem::copy_file(dir + "/train/t.yelan.h5", dir + "/val/v.yelan.h5");
}

}  // namespace

TEST_CASE("train: --windows-per-visit decides the windows drawn, is kept in run.json, and --resume keeps to it", "[train][cli]") {
  yelan::test::CliTempDir d("train-visit");
  one_recording_dataset(d / "ds", "0.6s");
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> v = {"train", "--stage", "mask", "--config", "micro", "--data", d / "ds", "--mask-frames", "1",
                                  "--epoch-steps", "4", "--val-windows", "1", "--batch", "2", "--threads", "1",
                                  "-o", d / out, "--steps", "4"};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  auto losses = [&](const std::string& out) {  // the training loss column, step by step
    std::istringstream in(yelan::test::slurp(d / (out + "/log.csv")));
    std::string line, all;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::istringstream l(line);
      std::string c;
      for (int k = 0; k < 3; ++k) std::getline(l, c, ',');
      all += c + ";";
    }
    return all;
  };
  const auto one = run("one", {"--windows-per-visit", "1"}), eight = run("eight", {});
  INFO(one.err);
  REQUIRE(one.code == 0);
  REQUIRE(eight.code == 0);
  // Same seed, same recording, other windows: the first step already trains on others.
  CHECK(losses("one") != losses("eight"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "one/run.json"), "\"windows_per_visit\": 1,"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "eight/run.json"), "\"windows_per_visit\": 8,"));
  // Interrupted at step 2 and resumed with its own N: the uninterrupted run, byte for byte;
  // resumed with another N: refused, naming the N to give.
  REQUIRE(run("b", {"--windows-per-visit", "1", "--stop-at", "2"}).code == 0);
  const auto other = run("b", {"--windows-per-visit", "3", "--resume"});
  CHECK(other.code != 0);
  CHECK(yelan::test::contains(other.err, "--windows-per-visit 1"));
  // So is a resume with an augmentation the run did not have (--flip: mirrored windows).
  const auto mirrored = run("b", {"--windows-per-visit", "1", "--flip", "--resume"});
  CHECK(mirrored.code != 0);
  CHECK(yelan::test::contains(mirrored.err, "trained without --flip"));
  REQUIRE(run("b", {"--windows-per-visit", "1", "--resume"}).code == 0);
  CHECK(yelan::test::slurp(d / "b/final.h5") == yelan::test::slurp(d / "one/final.h5"));
  CHECK(run("zero", {"--windows-per-visit", "0"}).code == 2);
  // The batch's two windows read on two threads (both cursors in the one file): the same
  // windows, so the same weights byte for byte.
  REQUIRE(run("eight-r2", {"--read-threads", "2"}).code == 0);
  CHECK(yelan::test::slurp(d / "eight-r2/final.h5") == yelan::test::slurp(d / "eight/final.h5"));
  CHECK(run("r0", {"--read-threads", "0"}).code == 2);
  // --flip mirrors some of the same windows: other losses, and run.json says so.
  REQUIRE(run("f", {"--windows-per-visit", "1", "--flip"}).code == 0);
  CHECK(losses("f") != losses("one"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "f/run.json"), "\"flip\": true,"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "one/run.json"), "\"flip\": false,"));
  const auto sim = yelan::test::run_cli({"train", "--stage", "mask", "--config", "micro", "--sim", "ben-dance3-front-high-static",
                                         "-o", d / "s", "--steps", "1", "--windows-per-visit", "2"});
  CHECK(sim.code == 2);
  CHECK(yelan::test::contains(sim.err, "--data only"));
}

TEST_CASE("train: --validate-start logs the starting weights' validation as step 0 and trains as a run without it", "[train][cli]") {
  yelan::test::CliTempDir d("train-vstart");
  one_recording_dataset(d / "ds", "0.6s");
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> v = {"train", "--stage", "pose", "--config", "micro", "--data", d / "ds", "--epoch-steps", "2",
                                  "--val-windows", "2", "--batch", "2", "--threads", "1", "-o", d / out, "--steps", "4"};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  auto rows = [&](const std::string& out) {  // step, training loss, validation loss, validation MPJPE
    std::istringstream in(yelan::test::slurp(d / (out + "/log.csv")));
    std::vector<std::vector<std::string>> all;
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::istringstream l(line);
      std::vector<std::string> c(11);
      for (auto& x : c) std::getline(l, x, ',');
      all.push_back({c[0], c[2], c[3], c[8]});
    }
    return all;
  };
  const auto plain = run("plain", {});
  const auto start = run("start", {"--validate-start"});
  INFO(start.err);
  REQUIRE(plain.code == 0);
  REQUIRE(start.code == 0);
  CHECK(yelan::test::contains(start.err, "step 0 (the start): validation "));
  CHECK_FALSE(yelan::test::contains(plain.err, "step 0 (the start)"));
  const auto p = rows("plain"), s = rows("start");
  REQUIRE(p.size() == 4);
  REQUIRE(s.size() == 5);
  CHECK(s[0][0] == "0");
  CHECK(s[0][1] == "-1");                 // no training step behind it
  CHECK(std::stod(s[0][3]) > 0);          // an MPJPE in mm
  CHECK(s[0][2] != s[2][2]);              // the untrained net scores otherwise than after two steps
  for (std::size_t k = 0; k < p.size(); ++k) CHECK(s[k + 1] == p[k]);  // the same run after it
  CHECK(yelan::test::slurp(d / "start/final.h5") == yelan::test::slurp(d / "plain/final.h5"));
  CHECK(yelan::test::slurp(d / "start/best.h5") == yelan::test::slurp(d / "plain/best.h5"));
  // Stopped and resumed: the step-0 row once, the rest as the whole run.
  REQUIRE(run("b", {"--validate-start", "--stop-at", "2"}).code == 0);
  REQUIRE(run("b", {"--validate-start", "--resume"}).code == 0);
  CHECK(rows("b") == s);
}

TEST_CASE("train: --freeze-bn keeps the pose net's BatchNorm statistics and trains the rest, is kept in run.json, resumes bit-exactly", "[train][cli]") {
  yelan::test::CliTempDir d("train-freeze-bn");
  one_recording_dataset(d / "ds", "0.6s");
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> v = {"train", "--stage", "pose", "--config", "micro", "--data", d / "ds", "--epoch-steps", "2",
                                  "--val-windows", "1", "--batch", "2", "--threads", "1", "-o", d / out, "--steps", "3"};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  REQUIRE(run("start", {}).code == 0);
  const std::string init = d / "start/final.h5";
  const auto frozen = run("f", {"--init", init, "--freeze-bn"});
  INFO(frozen.err);
  REQUIRE(frozen.code == 0);
  REQUIRE(run("g", {"--init", init}).code == 0);
  namespace w = yelan::weights;
  const w::Weights ws = w::load_weights(init), wf = w::load_weights(d / "f/final.h5"), wg = w::load_weights(d / "g/final.h5");
  const auto &s0 = ws.groups.at("pose"), &f = wf.groups.at("pose"), &g = wg.groups.at("pose");
  int stats = 0, stats_moved_unfrozen = 0, params_moved = 0;
  for (const auto& [k, t] : s0) {
    if (w::is_parameter(k)) {
      params_moved += f.at(k).data != t.data;
    } else {
      ++stats;
      CHECK(f.at(k).data == t.data);  // running mean, variance, batches tracked: the start's
      stats_moved_unfrozen += g.at(k).data != t.data;
    }
  }
  CHECK(stats > 0);
  CHECK(stats_moved_unfrozen == stats);  // without the flag every one of them moves
  CHECK(params_moved > 0);
  CHECK(yelan::test::contains(yelan::test::slurp(d / "f/run.json"), "\"freeze_bn\": true,"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "g/run.json"), "\"freeze_bn\": false,"));
  // Stopped and resumed with the flag: the uninterrupted run; without it: refused.
  REQUIRE(run("b", {"--init", init, "--freeze-bn", "--stop-at", "1"}).code == 0);
  const auto unfrozen = run("b", {"--init", init, "--resume"});
  CHECK(unfrozen.code != 0);
  CHECK(yelan::test::contains(unfrozen.err, "trained with --freeze-bn"));
  REQUIRE(run("b", {"--init", init, "--freeze-bn", "--resume"}).code == 0);
  CHECK(yelan::test::slurp(d / "b/final.h5") == yelan::test::slurp(d / "f/final.h5"));
  const auto mask = yelan::test::run_cli({"train", "--stage", "mask", "--config", "micro", "--data", d / "ds", "-o", d / "m",
                                          "--steps", "1", "--freeze-bn"});
  CHECK(mask.code == 2);
  CHECK(yelan::test::contains(mask.err, "--stage pose only"));
}

TEST_CASE("train: --mask-reuse masks stage 2 as early exit does, is kept in run.json, resumes bit-exactly, needs --mask-weights", "[train][cli]") {
  yelan::test::CliTempDir d("train-reuse");
  one_recording_dataset(d / "ds", "0.8s");
  REQUIRE(yelan::test::run_cli({"weights", "init", "--config", "micro", "-o", d / "m.h5", "--seed", "3"}).code == 0);
  auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> v = {"train", "--stage", "pose", "--config", "micro", "--data", d / "ds", "--mask-weights", d / "m.h5",
                                  "--epoch-steps", "3", "--val-windows", "2", "--batch", "2", "--threads", "1",
                                  "--windows-per-visit", "1", "-o", d / out, "--steps", "3"};
    v.insert(v.end(), extra.begin(), extra.end());
    return yelan::test::run_cli(v);
  };
  const auto reuse = run("r", {"--mask-reuse", "3"}), fresh = run("f", {});
  INFO(reuse.err);
  REQUIRE(reuse.code == 0);
  REQUIRE(fresh.code == 0);
  CHECK(yelan::test::contains(yelan::test::slurp(d / "r/run.json"), "\"mask_reuse\": 3,"));
  CHECK(yelan::test::contains(yelan::test::slurp(d / "f/run.json"), "\"mask_reuse\": 0,"));
  CHECK(yelan::test::slurp(d / "r/final.h5") != yelan::test::slurp(d / "f/final.h5"));  // other inputs, other steps
  // Stopped at step 1 and resumed: the uninterrupted run; resumed with another N: refused.
  REQUIRE(run("b", {"--mask-reuse", "3", "--stop-at", "1"}).code == 0);
  const auto other = run("b", {"--mask-reuse", "2", "--resume"});
  CHECK(other.code != 0);
  CHECK(yelan::test::contains(other.err, "--mask-reuse 3"));
  REQUIRE(run("b", {"--mask-reuse", "3", "--resume"}).code == 0);
  CHECK(yelan::test::slurp(d / "b/final.h5") == yelan::test::slurp(d / "r/final.h5"));
  // More than the config's future masks (micro: 3), or no mask net to reuse: usage errors.
  CHECK(run("big", {"--mask-reuse", "4"}).code == 2);
  const auto no_net = yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--data", d / "ds", "--mask-reuse", "2",
                                            "-o", d / "n", "--steps", "1"});
  CHECK(no_net.code == 2);
  CHECK(yelan::test::contains(no_net.err, "--mask-weights"));
}

TEST_CASE("train: the validation windows come from every recording of the val split in turn", "[train][cli]") {
  yelan::test::CliTempDir d("train-val-spread");
  std::filesystem::create_directories(d / "ds/train");
  std::filesystem::create_directories(d / "ds/val");
  const std::string rec = d / "ds/train/t.yelan.h5";
  REQUIRE(yelan::test::run_cli({"sim", "--preset", "ben-dance3-front-high-static", "--duration", "0.4s", "-o", rec}).code == 0);
  // Twelve validation recordings (copies under their own names): the training stream's 8
  // cursors would draw 12 windows from at most 8 of them.
  for (int i = 0; i < 12; ++i)
    std::filesystem::copy_file(rec, d / ("ds/val/v" + std::to_string(100 + i) + ".yelan.h5"));
  const auto r = yelan::test::run_cli({"train", "--stage", "pose", "--config", "micro", "--data", d / "ds", "--epoch-steps", "1",
                                       "--val-windows", "12", "--batch", "8", "-o", d / "run", "--steps", "1"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(yelan::test::contains(r.err, "validation: 12 windows from 12 of 12 recordings"));
}

#include "camera/sim/presets.h"
#include "camera/sim/window_stream.h"
#include "engine/train/batch.h"

TEST_CASE("train: baseline inputs: unmasked TORE for masked_input false, log counts for the counts representation", "[train]") {
  namespace sim = yelan::camera::sim;
  const yelan::ModelConfig nomask = yelan::load_model_config(std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/small-nomask.json");
  const yelan::ModelConfig frames = yelan::load_model_config(std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/small-frames-plain.json");
  sim::WindowStreamOptions o;
  o.window = nomask.window;
  o.warmup_s = 0.04;
  o.scene_s = 0.04 + o.window / o.frame_hz + 1e-6;
  o.counts = true;
  sim::SimWindowStream stream({sim::preset_spec("ben-dance7-front-high-static")}, 5, o);
  sim::SimWindow w;
  stream.next(w);
  yelan::MaskNet unused(nomask);
  const int H = nomask.height(), W = nomask.width(), d = nomask.downscale;
  // Asked for the true mask, a config without stage 2 masking still sees the whole TORE.
  BatchBuilder b(nomask, 1, MaskSource::truth);
  CHECK(b.source() == MaskSource::unmasked);
  b.add(w, unused, nullptr);
  yelan::layers::ActBuf want;
  want.resize(nomask.window, 6, H, W);
  for (int t = 0; t < nomask.window; ++t) yelan::input::downscale_tore(w.frames[std::size_t(t)].tore, 260, 346, d, want.act, t);
  REQUIRE(b.batch().input.act.floats() == want.act.floats());
  CHECK(std::equal(want.act.data, want.act.data + want.act.floats(), b.batch().input.act.data));
  // Counts: 2 planes of log(1 + n), averaged over each d x d cell.
  BatchBuilder c(frames, 1, MaskSource::truth);
  c.add(w, unused, nullptr);
  const yelan::layers::Act& a = c.batch().input.act;
  REQUIRE(a.c == 2);
  const auto& n = w.frames[3].counts;
  double lit = 0;
  for (int p = 0; p < 2; ++p)
    for (int y = 0; y < H; y += 7)
      for (int x = 0; x < W; x += 5) {
        double s = 0;
        for (int dy = 0; dy < d; ++dy)
          for (int dx = 0; dx < d; ++dx) s += std::log1p(n[std::size_t(p) * 346 * 260 + std::size_t(y * d + dy) * 346 + x * d + dx]);
        const float got = a.data[((std::size_t(3) * a.cb()) * a.pixels() + std::size_t(y) * W + x) * 16 + p];
        REQUIRE(got == Approx(s / (d * d)).margin(1e-6));
        lit += s;
      }
  CHECK(lit > 0);
}

TEST_CASE("train: downscale_tore is the plain mean of each cell, bit for bit, on odd sizes and factors", "[train]") {
  for (const auto& [C, sh, sw, d] : {std::array<int, 4>{6, 7, 9, 2}, {6, 5, 11, 3}, {17, 3, 4, 1}, {2, 8, 8, 4}, {1, 1, 1, 1}}) {
    std::vector<float> vol(std::size_t(C) * sh * sw);
    for (std::size_t i = 0; i < vol.size(); ++i) vol[i] = float(std::sin(0.37 * double(i) + 1.0)) * 1.7f;
    const int H = sh / d, W = sw / d;
    yelan::layers::ActBuf got;
    got.resize(2, C, H, W);
    yelan::input::downscale_tore(vol, sh, sw, d, got.act, 1);
    for (int c = 0; c < C; ++c)
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          float s = 0;
          for (int dy = 0; dy < d; ++dy)
            for (int dx = 0; dx < d; ++dx) s += vol[std::size_t(c) * sh * sw + std::size_t(y * d + dy) * sw + x * d + dx];
          const float* frame1 = got.act.data + std::size_t(got.act.cb()) * got.act.pixels() * 16;
          REQUIRE(frame1[(std::size_t(c / 16) * got.act.pixels() + std::size_t(y) * W + x) * 16 + c % 16] == s * (1.f / float(d * d)));
          // frame 0 stays untouched (zero)
          REQUIRE(got.act.data[(std::size_t(c / 16) * got.act.pixels() + std::size_t(y) * W + x) * 16 + c % 16] == 0.f);
        }
  }
}

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

TEST_CASE("train: SIGINT or SIGTERM writes a checkpoint at the step reached and --resume continues from it", "[train][cli]") {
  for (const int sig : {SIGINT, SIGTERM}) {
    yelan::test::CliTempDir d("train-signal");
    const std::string out = d / "run";
    const std::vector<std::string> args = {"train", "--stage", "pose", "--config", "micro", "--sim",
                                           "ben-dance3-front-high-static", "--steps", "100000", "--batch", "1",
                                           "--epoch-steps", "100000", "--val-windows", "1", "-o", out, "--quiet",
                                           "--threads", "1"};
    const pid_t child = yelan::test::spawn(YELAN_BINARY, args);
    REQUIRE(child > 0);
    auto rows = [&] {
      std::istringstream in(yelan::test::slurp(out + "/log.csv"));
      int n = 0;
      for (std::string l; std::getline(in, l);) n += !l.empty() && l[0] != 's';
      return n;
    };
    for (int i = 0; i < 3000 && rows() < 3; ++i) ::usleep(10000);
    REQUIRE(rows() >= 3);
    ::kill(child, sig);
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
    const int reached = rows();
    CHECK(std::filesystem::exists(out + "/checkpoint.state"));
    auto resumed_args = args;
    resumed_args[8] = std::to_string(reached + 2);  // --steps
    resumed_args.push_back("--resume");
    const auto r = yelan::test::run_cli(resumed_args);
    INFO(r.err);
    CHECK(r.code == 0);
    CHECK(yelan::test::contains(r.err, "at step " + std::to_string(reached)));
  }
}

TEST_CASE("train: eval --data says stage 1's IoU on the recordings with a dancer beside the pooled one", "[train][cli]") {
  yelan::test::CliTempDir d("eval-people");
  REQUIRE(yelan::test::run_cli({"weights", "init", "--config", "micro", "--seed", "2", "-o", d / "w.h5"}).code == 0);
  REQUIRE(yelan::test::run_cli({"sim", "--dataset", d / "ds", "--seed", "3", "--train", "0", "--val", "1", "--test", "0",
                                "--val-empty", "1", "--duration", "0.6s", "--threads", "1"})
              .code == 0);
  const auto ev = yelan::test::run_cli({"eval", "--weights", d / "w.h5", "--data", d / "ds/val", "--seconds", "0.3",
                                        "--no-floors", "--json", d / "e.json"});
  INFO(ev.err);
  REQUIRE(ev.code == 0);
  CHECK(yelan::test::contains(ev.out, "(recordings with a dancer alone: "));
  const auto j = nlohmann::json::parse(yelan::test::slurp(d / "e.json"));
  const auto& people = j.at("mask_iou_by_condition").at("people");
  REQUIRE(people.contains("dancer"));
  // An untrained net draws a mask in the empty scene too: it never overlaps a true mask, so
  // it scores 0 there and pulls the pooled figure under the dancers' own.
  REQUIRE(people.contains("nobody"));
  CHECK(people.at("nobody").get<double>() == 0);
  CHECK(j.at("mask_iou").get<double>() < people.at("dancer").get<double>());
  // The IoU off the true outline's edge beside it, per condition too.
  CHECK(yelan::test::contains(ev.out, "; off the true outline's edge "));
  REQUIRE(j.at("mask_iou_off_edge").is_number());
  CHECK(j.at("mask_iou_off_edge_by_condition").at("people").contains("dancer"));
  // And at the sensor's pixels: the empty scene's mask is all false pixels there too.
  CHECK(yelan::test::contains(ev.out, "; at the sensor's pixels "));
  REQUIRE(j.at("mask_iou_sensor_px").is_number());
  const auto& px = j.at("mask_iou_sensor_px_by_condition").at("people");
  CHECK(px.at("nobody").get<double>() == 0);
  CHECK(px.at("dancer").get<double>() > 0);
  CHECK(j.at("mask_iou_sensor_px").get<double>() < px.at("dancer").get<double>());
}
