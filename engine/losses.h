// The training losses of SPEC section 6, as the reference code computes them
// (scripts/model/losses.py, unet_interface.py of miracleyoo/yelan-dynamic-dvs-hpe):
//
// HPE, per stage t: over joints j of frames n with valid[n][j],
//   e = |joints_t - target| (3D, normalised units) + JS(xy_t, G(x, y)) + JS(zy_t, G(z, y))
//       + JS(xz_t, G(x, z)),  joints_t = DSNT of stage t's maps,
//   G(u, v) a Gaussian of sigma 1 heatmap pixel at (u, v) on the pixel-centre grid,
//   normalised to sum 1; KL(p, q) = sum p (log(p + 1e-24) - log(q + 1e-24));
//   L_t = sum valid e / max(sum valid, 1);   L = mean over stages.
// Mask: BCE(logits[:, 0], labels[:, 0]) + BCE(logits, labels) + MSE(scores, s*), both BCE
//   means over their elements, s* = 1 - mean over pixels |sigmoid(logits) - labels| (no
//   gradient through s*).
#pragma once
#include <array>
#include <vector>

#include "engine/joints.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"

namespace yelan {

struct HpeLoss {
  double total = 0;
  std::vector<double> per_stage;  // L_t
  std::vector<double> euclid;     // the distance part of each stage
  int groups = 0, swapped = 0;    // swap_group > 0: groups scored, and of them against the swapped target
};

// Computes the loss of the net's last forward and fills dheat (one entry per stage:
// xy, zy, xz gradient maps, storage in `store`). target: n x J x 3, valid: n x J (0/1).
// swap_group > 0 (not the paper's; the 13 joints of SPEC only): the frames in groups of
// that many (a window), each group scored against its target or the target with left and
// right traded, whichever the last stage's joints are nearer to (summed distance): a net
// that cannot tell a dancer's back from the front may commit to either labelling instead of
// hedging between the hands, so whether it can place the limbs at all is seen apart.
HpeLoss hpe_loss(const PoseNet& net, int stages, const float* target, const float* valid,
                 std::vector<PoseNet::StageGrads>& dheat, std::vector<layers::Floats>& store, int swap_group = 0);

struct MaskLoss {
  double total = 0, bce_first = 0, bce_all = 0, score_mse = 0;
  double bce_focus = 0;  // the mean per-pixel BCE of masks 1..focus, times focus (0 without focus)
  // Soft Dice loss of the current mask, 1 - (2 sum(p y) + 1) / (sum p + sum y + 1) per sample
  // (p the sigmoid; +1: a pixel's worth, so an empty label and an empty mask score 0),
  // weighted mean over the samples; always reported, in total only times dice_weight.
  double dice = 0;
};

// labels: the same blocked layout and shape as net.masks(). dmasks gets dL/dlogits;
// dscores (n x N) dL/dscores. sample_weights (n, or empty for 1 each): every term is a
// weighted mean over the samples, sum w_i x_i / sum w_i, so the loss stays on the scale of
// the unweighted one while some samples pull harder than others. dice_weight > 0 adds the
// Dice term: the dancer covers a few percent of the frame, so per-pixel BCE is mostly the
// background's, while Dice scores the overlap that the mask IoU measures.
// focus K > 0: the future masks 1..K weigh as the current one does (a full per-pixel BCE term
// each, in bce_focus), where otherwise each future mask is one N-th of bce_all: early exit
// under an age cap K reuses masks 0..K-1 alone, so those are what the deployed IoU reads.
MaskLoss mask_loss(const MaskNet& net, const layers::Act& labels, const layers::Act& dmasks,
                   std::vector<float>& dscores, const std::vector<float>& sample_weights = {},
                   double dice_weight = 0, int focus = 0);

// One weight per sample: `nobody` where the sample's current-frame label (channel 0) is
// empty (a scene with nobody in the picture), 1 elsewhere. Stage 1's false alarms are whole
// empty rooms where it draws a dancer-sized blob; weighting them asks it to stop.
std::vector<float> nobody_weights(const layers::Act& labels, float nobody);

// The normalised target Gaussian of one joint on an h x w map (sum 1), as a plain array.
void target_gaussian(float mu_w, float mu_h, int h, int w, float sigma_px, float* out);

}  // namespace yelan
