// BVH retargeting. Per frame the clip's local joint rotations are stored as quaternions; at(t)
// slerps them (and lerps position channels) between the two nearest frames, runs FK in the
// file's frame, and rebuilds our skeleton bone by bone: direction from the clip, length from
// body_proportions(). The root trajectory is scaled by our leg length / the clip's.
#include "camera/sim/motion.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace yelan::camera::sim {

Motion::~Motion() = default;

// Segment lengths as fractions of standing height H. Drillis & Contini (1966), as drawn in
// Winter, "Biomechanics and Motor Control of Human Movement": shoulder height 0.818H, hip
// (trochanter) 0.530H, knee 0.285H, ankle 0.039H, elbow 0.630H, wrist 0.485H, finger tip
// 0.377H, chin 0.870H, shoulder width 0.259H, foot length 0.152H; hence upper arm 0.186H,
// forearm 0.146H, hand 0.108H, thigh 0.245H, shank 0.246H.
// Our own choices where the table has no segment: chest (lower ribs) at 0.660H; skull centre
// at 0.935H (midway chin..top) with the top 0.065H above it; ankle -> toe tip 0.120H (0.75 of
// the foot forward, down to the floor); hip-joint centres 0.110H apart (they lie inside the
// 0.191H trochanter width). Female: shoulders 0.245H wide and hip joints 0.120H apart (a
// narrower shoulder girdle and wider pelvis; an approximation, not from the table).
BodyProportions body_proportions(const BodyShape& shape) {
  const double h = shape.height_mm;
  BodyProportions p{};
  p.pelvis_chest = (0.660 - 0.530) * h;
  p.chest_neck = (0.818 - 0.660) * h;
  p.neck_head = (0.935 - 0.818) * h;
  p.head_top = 0.065 * h;
  p.nose_fwd = 0.062 * h;
  p.nose_up = -0.010 * h;
  p.chin_fwd = 0.040 * h;
  p.chin_up = -0.060 * h;
  p.head_nose = std::hypot(p.nose_fwd, p.nose_up);
  p.head_chin = std::hypot(p.chin_fwd, p.chin_up);
  p.half_shoulder = (shape.female ? 0.245 : 0.259) * h / 2;
  p.upper_arm = 0.186 * h;
  p.forearm = 0.146 * h;
  p.hand = 0.108 * h;
  p.half_hip = (shape.female ? 0.120 : 0.110) * h / 2;
  p.thigh = 0.245 * h;
  p.shank = 0.246 * h;
  p.foot = 0.120 * h;
  p.ankle_height = 0.039 * h;
  p.hip_height = 0.530 * h;
  return p;
}

std::vector<Bone> body_bones(const BodyShape& shape) {
  const BodyProportions p = body_proportions(shape);
  std::vector<Bone> b = {{kPelvis, kChest, p.pelvis_chest}, {kChest, kNeck, p.chest_neck},
                         {kNeck, kHead, p.neck_head},       {kHead, kHeadTop, p.head_top},
                         {kHead, kNose, p.head_nose},       {kHead, kChin, p.head_chin}};
  for (int s = 0; s < 2; ++s) {
    auto P = [s](BodyPoint right) { return BodyPoint(right + s); };
    b.push_back({kNeck, P(kShoulderR), p.half_shoulder});
    b.push_back({P(kShoulderR), P(kElbowR), p.upper_arm});
    b.push_back({P(kElbowR), P(kWristR), p.forearm});
    b.push_back({P(kWristR), P(kHandTipR), p.hand});
    b.push_back({kPelvis, P(kHipR), p.half_hip});
    b.push_back({P(kHipR), P(kKneeR), p.thigh});
    b.push_back({P(kKneeR), P(kAnkleR), p.shank});
    b.push_back({P(kAnkleR), P(kToeR), p.foot});
  }
  return b;
}

constexpr double kPi = 3.14159265358979323846;

BodyPose mirror_pose(const BodyPose& pose) {
  BodyPose m = pose;
  for (auto& v : m.p) v.x() = -v.x();
  for (int i = kShoulderR; i < kBodyPointCount; i += 2) std::swap(m.p[i], m.p[i + 1]);
  return m;
}

namespace {
// Columns: across (left shoulder -> right), forward, up (chest -> neck); orthonormal.
Eigen::Matrix3d chest_frame(const BodyPose& p) {
  const Vec3 up = (p.p[kNeck] - p.p[kChest]).normalized();
  Vec3 across = p.p[kShoulderR] - p.p[kShoulderL];
  across = (across - across.dot(up) * up).normalized();
  Eigen::Matrix3d f;
  f.col(0) = across;
  f.col(1) = up.cross(across);
  f.col(2) = up;
  return f;
}
}  // namespace

BodyPose with_arm_from(const BodyPose& body, const BodyPose& arms, int side) {
  if (side != 0 && side != 1) throw std::invalid_argument("with_arm_from: side must be 0 (right) or 1 (left)");
  const Eigen::Matrix3d turn = chest_frame(body) * chest_frame(arms).transpose();
  BodyPose out = body;
  for (int point : kRightArmPoints)
    out.p[point + side] = body.p[kNeck] + turn * (arms.p[point + side] - arms.p[kNeck]);
  return out;
}

Eigen::Matrix3d turn_to_face_minus_y(const BodyPose& pose) {
  const Vec3 f = (pose.p[kHipL] - pose.p[kHipR]).cross(Vec3::UnitZ());
  return Eigen::AngleAxisd(-kPi / 2 - std::atan2(f.y(), f.x()), Vec3::UnitZ()).toRotationMatrix();
}

namespace {

// ---------------------------------------------------------------- name mapping

std::string base_name(const std::string& name) {
  std::string s = name.substr(name.rfind(':') == std::string::npos ? 0 : name.rfind(':') + 1);
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Candidate names, highest priority first, written for the left side; the right side's
// are derived by left->right and a leading l->r.
const std::vector<std::string> kHipNames = {"leftupleg", "lfemur", "leftupperleg", "leftthigh", "lefthip", "l_hip"};
const std::vector<std::string> kKneeNames = {"leftleg", "ltibia", "leftlowerleg", "leftknee", "leftshin", "l_knee"};
const std::vector<std::string> kAnkleNames = {"leftfoot", "lfoot", "leftankle", "l_ankle"};
const std::vector<std::string> kToeNames = {"lefttoebase", "ltoes", "lefttoe", "l_toe"};
// "LeftShoulder" is the clavicle in CMU and Mixamo rigs, so it is only a last resort.
const std::vector<std::string> kShoulderNames = {"leftarm", "lhumerus", "leftupperarm", "l_shoulder", "leftshoulder"};
const std::vector<std::string> kElbowNames = {"leftforearm", "lradius", "leftlowerarm", "leftelbow", "l_elbow"};
const std::vector<std::string> kWristNames = {"lefthand", "lwrist", "leftwrist", "l_wrist", "lhand"};
const std::vector<std::string> kNeckNames = {"neck", "lowerneck", "neck1", "neck01"};
const std::vector<std::string> kHeadNames = {"head"};

std::string to_right(const std::string& left) {
  std::string s = left;
  if (auto k = s.find("left"); k != std::string::npos) return s.replace(k, 4, "right");
  if (s.rfind("l_", 0) == 0) return "r_" + s.substr(2);
  if (!s.empty() && s[0] == 'l') s[0] = 'r';
  return s;
}

int find_role(const BvhClip& clip, const std::vector<std::string>& names, bool right) {
  for (const std::string& n : names) {
    const std::string want = right ? to_right(n) : n;
    for (std::size_t i = 0; i < clip.joints.size(); ++i)
      if (!clip.joints[i].end_site && base_name(clip.joints[i].name) == want) return int(i);
  }
  return -1;
}

int end_site_of(const BvhClip& clip, int joint) {
  for (std::size_t i = 0; i < clip.joints.size(); ++i)
    if (clip.joints[i].parent == joint && clip.joints[i].end_site) return int(i);
  return -1;
}

bool is_ancestor(const BvhClip& clip, int a, int j) {
  for (j = clip.joints[j].parent; j >= 0; j = clip.joints[j].parent)
    if (j == a) return true;
  return false;
}

std::string join(const std::vector<std::string>& v, bool right) {
  std::string s;
  for (const auto& n : v) s += (s.empty() ? "" : "/") + (right ? to_right(n) : n);
  return s;
}

}  // namespace

BvhBodyMap map_bvh_body(const BvhClip& clip) {
  BvhBodyMap m{};
  std::string missing;
  auto need = [&](const std::vector<std::string>& names, bool right, const char* part) {
    const int j = find_role(clip, names, right);
    if (j < 0) missing += std::string(missing.empty() ? "" : "; ") + part + " (tried " + join(names, right) + ")";
    return j;
  };
  for (int s = 0; s < 2; ++s) {
    const bool r = s == 0;
    const char* side = r ? "right " : "left ";
    m.hip[s] = need(kHipNames, r, (std::string(side) + "hip").c_str());
    m.knee[s] = need(kKneeNames, r, (std::string(side) + "knee").c_str());
    m.ankle[s] = need(kAnkleNames, r, (std::string(side) + "ankle").c_str());
    m.shoulder[s] = need(kShoulderNames, r, (std::string(side) + "shoulder").c_str());
    m.elbow[s] = need(kElbowNames, r, (std::string(side) + "elbow").c_str());
    m.wrist[s] = need(kWristNames, r, (std::string(side) + "wrist").c_str());
    m.toe[s] = find_role(clip, kToeNames, r);
    m.toe_tip[s] = -1;
    if (m.toe[s] >= 0) {
      const int e = end_site_of(clip, m.toe[s]);
      m.toe_tip[s] = e >= 0 ? e : m.toe[s];
    } else if (m.ankle[s] >= 0) {
      m.toe_tip[s] = end_site_of(clip, m.ankle[s]);
      if (m.toe_tip[s] < 0)
        missing += std::string(missing.empty() ? "" : "; ") + side + "toe (tried " + join(kToeNames, r) +
                   " or an End Site on the ankle)";
    }
  }
  m.neck = need(kNeckNames, false, "neck");
  m.head = need(kHeadNames, false, "head");
  if (!missing.empty())
    throw BvhError(clip.path, 0, 1, "BVH hierarchy not recognised, missing: " + missing);
  // Head top: the farthest descendant of the head in the rest pose (End Site, HeadTop_End).
  const auto rest = bvh_rest_positions(clip);
  m.head_top = -1;
  double best = 1e-9;
  for (std::size_t i = 0; i < clip.joints.size(); ++i)
    if (is_ancestor(clip, m.head, int(i)) && (rest[i] - rest[m.head]).norm() > best)
      best = (rest[i] - rest[m.head]).norm(), m.head_top = int(i);
  // Chest: the lowest spine joint (ancestor of the neck, not the root) at least 35% of the
  // way up from the hip joints to the neck and not at the neck itself. CMU's Spine1 sits on
  // its Neck, so this picks Spine there; Mixamo's Spine1.
  const Eigen::Vector3d mid_hips = (rest[m.hip[0]] + rest[m.hip[1]]) / 2;
  const double rise = rest[m.neck].y() - mid_hips.y();
  m.chest = -1;
  double lowest = 1e300;
  for (int j = clip.joints[m.neck].parent; j > 0; j = clip.joints[j].parent) {
    const double h = rest[j].y() - mid_hips.y();
    if (h >= 0.35 * rise && (rest[j] - rest[m.neck]).norm() > 1e-3 * std::abs(rise) && h < lowest)
      lowest = h, m.chest = j;
  }
  return m;
}

std::array<Dhp19Source, kJointCount> dhp19_bvh_sources(const BvhClip& clip) {
  const BvhBodyMap m = map_bvh_body(clip);
  auto nm = [&](int j) { return clip.joints[j].name; };
  std::array<Dhp19Source, kJointCount> out;
  out[0] = {kHead, nm(m.head),
            "skull centre: midway between " + nm(m.head) + " and " +
                (m.head_top >= 0 ? nm(m.head_top) : std::string("itself")) + ", along the neck from " + nm(m.neck)};
  for (int s = 0; s < 2; ++s) {
    out[1 + s] = {BodyPoint(kShoulderR + s), nm(m.shoulder[s]), "joint position (humeral head)"};
    out[3 + s] = {BodyPoint(kElbowR + s), nm(m.elbow[s]), "joint position"};
    out[5 + s] = {BodyPoint(kHipR + s), nm(m.hip[s]), "joint position (hip joint centre)"};
    out[7 + s] = {BodyPoint(kWristR + s), nm(m.wrist[s]), "joint position (wrist; DHP19 'hand')"};
    out[9 + s] = {BodyPoint(kKneeR + s), nm(m.knee[s]), "joint position"};
    out[11 + s] = {BodyPoint(kAnkleR + s), nm(m.ankle[s]), "joint position (ankle; DHP19 'foot')"};
  }
  return out;
}

namespace {

Eigen::Vector3d unit_or(const Eigen::Vector3d& v, const Eigen::Vector3d& fallback) {
  const double n = v.norm();
  return n > 1e-12 ? Eigen::Vector3d(v / n) : fallback;
}

class BvhMotion final : public Motion {
 public:
  BvhMotion(BvhClip clip, const BodyShape& shape, const MotionOptions& opt)
      : clip_(std::move(clip)), opt_(opt), prop_(body_proportions(shape)) {
    if (!(opt.speed >= 0.5 && opt.speed <= 2.0))
      throw std::invalid_argument("motion speed must be in [0.5, 2], got " + std::to_string(opt.speed));
    map_ = map_bvh_body(clip_);
    first_ = opt.skip_first_frame && clip_.frame_count >= 2 ? 1 : 0;
    if (clip_.frame_count - first_ < 1) throw BvhError(clip_.path, 0, 1, "no frames to play");
    frames_ = clip_.frame_count - first_;
    const std::size_t nj = clip_.joints.size();
    for (std::size_t j = 0; j < nj; ++j)
      for (BvhChannel c : clip_.joints[j].channels)
        if (c <= BvhChannel::Zposition) { pos_joints_.push_back(int(j)); break; }
    rot_.resize(std::size_t(frames_) * nj);
    trans_.resize(std::size_t(frames_) * pos_joints_.size());
    for (int f = 0; f < frames_; ++f) {
      for (std::size_t j = 0; j < nj; ++j) rot_[f * nj + j] = bvh_local_rotation(clip_, int(j), first_ + f);
      for (std::size_t k = 0; k < pos_joints_.size(); ++k)
        trans_[f * pos_joints_.size() + k] = bvh_local_translation(clip_, pos_joints_[k], first_ + f);
    }
    rest_trans_.resize(nj);
    for (std::size_t j = 0; j < nj; ++j) rest_trans_[j] = clip_.joints[j].offset;
    setup_rest_frames();
    clip_.values.clear();
    clip_.values.shrink_to_fit();
    // Alignment from the unaligned pose at t = 0.
    const BodyPose p0 = retarget(0.0);
    if (opt.recentre) {
      align_ = turn_to_face_minus_y(p0);
      centre_ = Vec3(p0.p[kPelvis].x(), p0.p[kPelvis].y(), 0);
    }
    yaw_ = Eigen::AngleAxisd(opt.yaw_deg * kPi / 180, Vec3::UnitZ()).toRotationMatrix();
    std::string n = clip_.path.substr(clip_.path.find_last_of('/') == std::string::npos
                                          ? 0 : clip_.path.find_last_of('/') + 1);
    name_ = n;
  }

  double duration_s() const override { return (frames_ - 1) * clip_.frame_time_s / opt_.speed; }
  std::string name() const override { return name_; }

  BodyPose at(double t) const override {
    BodyPose p = retarget(std::clamp(t, 0.0, duration_s()) * opt_.speed);
    for (auto& v : p.p) v = align_ * (v - centre_);
    if (opt_.mirror) p = mirror_pose(p);
    for (auto& v : p.p) v = yaw_ * v;
    return p;
  }

 private:
  // Rest-pose vectors the head and hands need, in those joints' own frames (the rest pose has
  // identity rotations, so rest offsets are already in those frames).
  void setup_rest_frames() {
    const auto rest = bvh_rest_positions(clip_);
    const BvhBodyMap& m = map_;
    const Eigen::Vector3d up_rest = m.head_top >= 0 ? Eigen::Vector3d(rest[m.head_top] - rest[m.head])
                                                    : Eigen::Vector3d(rest[m.head] - rest[m.neck]);
    head_half_ = up_rest / 2;
    head_up_ = unit_or(up_rest, Eigen::Vector3d::UnitY());
    // BVH rest facing from the hips: (left - right) x up.
    Eigen::Vector3d fwd = (rest[m.hip[1]] - rest[m.hip[0]]).cross(Eigen::Vector3d::UnitY());
    fwd -= fwd.dot(head_up_) * head_up_;
    head_fwd_ = unit_or(fwd, Eigen::Vector3d::UnitZ());
    for (int s = 0; s < 2; ++s) {
      // Hand direction: to the farthest rest point under the wrist, else along the forearm.
      Eigen::Vector3d best = rest[m.wrist[s]] - rest[m.elbow[s]];
      double d = 0;
      for (std::size_t i = 0; i < clip_.joints.size(); ++i)
        if (is_ancestor(clip_, m.wrist[s], int(i)) && (rest[i] - rest[m.wrist[s]]).norm() > d)
          d = (rest[i] - rest[m.wrist[s]]).norm(), best = rest[i] - rest[m.wrist[s]];
      hand_dir_[s] = unit_or(best, Eigen::Vector3d::UnitX());
    }
    auto leg = [&](int s) { return (rest[m.knee[s]] - rest[m.hip[s]]).norm() + (rest[m.ankle[s]] - rest[m.knee[s]]).norm(); };
    const double bvh_leg = (leg(0) + leg(1)) / 2;
    if (!(bvh_leg > 0)) throw BvhError(clip_.path, 0, 1, "legs of zero length in the rest pose");
    root_scale_ = (prop_.thigh + prop_.shank) / bvh_leg;
  }

  // Our pose at clip time s (seconds from the first played frame), before alignment.
  BodyPose retarget(double s) const {
    const std::size_t nj = clip_.joints.size(), np = pos_joints_.size();
    const double x = std::clamp(s / clip_.frame_time_s, 0.0, double(frames_ - 1));
    const int f0 = std::min(int(x), frames_ - 1), f1 = std::min(f0 + 1, frames_ - 1);
    const double a = x - f0;
    constexpr std::size_t kStack = 256;
    Eigen::Quaterniond lr_s[kStack], gr_s[kStack];
    Eigen::Vector3d lt_s[kStack], gp_s[kStack];
    std::vector<Eigen::Quaterniond> lr_h, gr_h;
    std::vector<Eigen::Vector3d> lt_h, gp_h;
    Eigen::Quaterniond *lr = lr_s, *gr = gr_s;
    Eigen::Vector3d *lt = lt_s, *gp = gp_s;
    if (nj > kStack) {  // rare huge rigs: heap
      lr_h.resize(nj), gr_h.resize(nj), lt_h.resize(nj), gp_h.resize(nj);
      lr = lr_h.data(), gr = gr_h.data(), lt = lt_h.data(), gp = gp_h.data();
    }
    const Eigen::Quaterniond* q0 = &rot_[f0 * nj];
    const Eigen::Quaterniond* q1 = &rot_[f1 * nj];
    for (std::size_t j = 0; j < nj; ++j) {
      // End Sites and CMU's uncaptured finger joints hold still: no slerp needed.
      lr[j] = a == 0 || q0[j].coeffs() == q1[j].coeffs() ? q0[j] : q0[j].slerp(a, q1[j]);
      lt[j] = rest_trans_[j];
    }
    for (std::size_t k = 0; k < np; ++k)
      lt[pos_joints_[k]] = (1 - a) * trans_[f0 * np + k] + a * trans_[f1 * np + k];
    bvh_forward_kinematics(clip_, lr, lt, gp, gr);

    const BvhBodyMap& m = map_;
    const BodyProportions& P = prop_;
    auto dir = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Vec3& fallback) {
      return unit_or(bvh_axes_to_world(to - from), fallback);
    };
    BodyPose out;
    auto& p = out.p;
    const Eigen::Vector3d mid_hips = (gp[m.hip[0]] + gp[m.hip[1]]) / 2;
    p[kPelvis] = root_scale_ * bvh_axes_to_world(mid_hips);
    const Vec3 up = Vec3::UnitZ();
    const Eigen::Vector3d chest_src = m.chest >= 0 ? gp[m.chest] : (mid_hips + gp[m.neck]) / 2;
    p[kChest] = p[kPelvis] + P.pelvis_chest * dir(mid_hips, chest_src, up);
    p[kNeck] = p[kChest] + P.chest_neck * dir(chest_src, gp[m.neck], up);
    const Eigen::Vector3d head_src = gp[m.head] + gr[m.head] * head_half_;
    p[kHead] = p[kNeck] + P.neck_head * dir(gp[m.neck], head_src, up);
    const Vec3 hu = bvh_axes_to_world(gr[m.head] * head_up_);
    const Vec3 hf = bvh_axes_to_world(gr[m.head] * head_fwd_);
    p[kHeadTop] = p[kHead] + P.head_top * hu;
    p[kNose] = p[kHead] + P.nose_fwd * hf + P.nose_up * hu;
    p[kChin] = p[kHead] + P.chin_fwd * hf + P.chin_up * hu;
    for (int sd = 0; sd < 2; ++sd) {
      const Vec3 lateral = sd == 0 ? Vec3(-1, 0, 0) : Vec3(1, 0, 0);
      const Vec3 down = -up;
      p[kShoulderR + sd] = p[kNeck] + P.half_shoulder * dir(gp[m.neck], gp[m.shoulder[sd]], lateral);
      p[kElbowR + sd] = p[kShoulderR + sd] + P.upper_arm * dir(gp[m.shoulder[sd]], gp[m.elbow[sd]], down);
      p[kWristR + sd] = p[kElbowR + sd] + P.forearm * dir(gp[m.elbow[sd]], gp[m.wrist[sd]], down);
      p[kHandTipR + sd] = p[kWristR + sd] + P.hand * bvh_axes_to_world(gr[m.wrist[sd]] * hand_dir_[sd]);
      p[kHipR + sd] = p[kPelvis] + P.half_hip * dir(mid_hips, gp[m.hip[sd]], lateral);
      p[kKneeR + sd] = p[kHipR + sd] + P.thigh * dir(gp[m.hip[sd]], gp[m.knee[sd]], down);
      p[kAnkleR + sd] = p[kKneeR + sd] + P.shank * dir(gp[m.knee[sd]], gp[m.ankle[sd]], down);
      p[kToeR + sd] = p[kAnkleR + sd] + P.foot * dir(gp[m.ankle[sd]], gp[m.toe_tip[sd]], Vec3(0, -1, 0));
    }
    return out;
  }

  BvhClip clip_;  // hierarchy only after construction (values dropped)
  MotionOptions opt_;
  BodyProportions prop_;
  BvhBodyMap map_{};
  int first_ = 0, frames_ = 0;
  std::vector<int> pos_joints_;
  std::vector<Eigen::Quaterniond> rot_;  // frames_ x joints
  std::vector<Eigen::Vector3d> trans_;   // frames_ x pos_joints_
  std::vector<Eigen::Vector3d> rest_trans_;
  Eigen::Vector3d head_half_, head_up_, head_fwd_, hand_dir_[2];
  double root_scale_ = 1;
  Eigen::Matrix3d align_ = Eigen::Matrix3d::Identity(), yaw_ = Eigen::Matrix3d::Identity();
  Vec3 centre_ = Vec3::Zero();
  std::string name_;
};

}  // namespace

std::unique_ptr<Motion> make_bvh_motion(BvhClip clip, const BodyShape& shape, const MotionOptions& opt) {
  return std::make_unique<BvhMotion>(std::move(clip), shape, opt);
}

std::unique_ptr<Motion> load_bvh_motion(const std::string& path, const BodyShape& shape, const MotionOptions& opt) {
  return make_bvh_motion(read_bvh(path), shape, opt);
}

}  // namespace yelan::camera::sim
