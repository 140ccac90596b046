// The simulator's shared vocabulary: the body's key points, character shape, render
// primitives, the camera and one rendered sample. Every room of camera/sim speaks these
// types, so motion (bvh, dance), body and clothing, the renderer and the pixel model can be
// built and tested apart.
//
// World frame: right-handed, millimetres, z up, floor at z = 0. A character's rest facing is
// -y (towards a "front" camera standing at negative y looking along +y).
// Camera frame: OpenCV (x right, y down, z forward), millimetres; M maps world -> camera.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace yelan::camera::sim {

using Vec3 = Eigen::Vector3d;

// Points of the body that motion produces and the body builder dresses. Seven on the axis,
// then seven pairs, right before left.
enum BodyPoint : int {
  kPelvis,    // midpoint of the hip joints
  kChest,     // spine at the level of the lower ribs
  kNeck,      // base of the neck, between the shoulders
  kHead,      // centre of the skull
  kHeadTop,   // top of the skull
  kNose,      // front of the face: gives the head's facing
  kChin,
  kShoulderR, kShoulderL,
  kElbowR, kElbowL,
  kWristR, kWristL,
  kHandTipR, kHandTipL,
  kHipR, kHipL,
  kKneeR, kKneeL,
  kAnkleR, kAnkleL,
  kToeR, kToeL,
  kBodyPointCount
};

struct BodyPose {
  std::array<Vec3, kBodyPointCount> p;  // world frame, mm
};

// The right arm's points, shoulder to finger tip; the left arm's are each one further.
inline constexpr std::array<BodyPoint, 4> kRightArmPoints = {kShoulderR, kElbowR, kWristR, kHandTipR};

// DHP19's 13 joints in SPEC order: head, shoulderR, shoulderL, elbowR, elbowL, hipR, hipL,
// handR, handL, kneeR, kneeL, footR, footL. hand = wrist, foot = ankle.
inline constexpr int kJointCount = 13;
inline constexpr std::array<BodyPoint, kJointCount> kDhp19Points = {
    kHead, kShoulderR, kShoulderL, kElbowR, kElbowL, kHipR, kHipL,
    kWristR, kWristL, kKneeR, kKneeL, kAnkleR, kAnkleL};
using Joints13 = std::array<Vec3, kJointCount>;
// Their names, as CSV headers and reports spell them.
inline constexpr std::array<const char*, kJointCount> kJointNames = {
    "head", "shoulderR", "shoulderL", "elbowR", "elbowL", "hipR", "hipL",
    "handR", "handL", "kneeR", "kneeL", "footR", "footL"};

inline Joints13 dhp19_joints(const BodyPose& pose) {
  Joints13 j;
  for (int i = 0; i < kJointCount; ++i) j[i] = pose.p[kDhp19Points[i]];
  return j;
}

// A character's shape. Motion retargets onto it (bone lengths from height and sex); the
// body builder uses girth for the flesh around the bones.
struct BodyShape {
  double height_mm = 1700;  // standing height, 1500..1950
  double girth = 1.0;       // radius multiplier of limbs and torso, 0.8..1.4
  bool female = false;
};

// Surface appearance. The DAVIS346 is monochrome, so albedo is one linear reflectance.
enum class Pattern : std::uint8_t { plain, stripes, checks, print };
struct Material {
  float albedo = 0.5f;     // linear reflectance, 0..1
  float albedo2 = 0.5f;    // second colour of the pattern
  Pattern pattern = Pattern::plain;
  float period_mm = 60;    // stripe/check period, print blob size
  // The pattern is evaluated in this frame, which moves with the surface it is printed on,
  // so texture edges move (and make events) as the body moves.
  Vec3 origin = Vec3::Zero();
  Vec3 u_axis = Vec3::UnitX();
  Vec3 v_axis = Vec3::UnitZ();
  std::uint32_t print_seed = 0;
};

enum class Shape : std::uint8_t {
  round_cone,  // capsule from a (radius ra) to b (radius rb); ra == rb is a plain capsule
  ellipsoid,   // centre a, semi-axes are the columns of `axes`
  quad,        // parallelogram: corner a, edges axes.col(0) and axes.col(1), seen from both sides
  cone_shell,  // open frustum (skirt, coat hem): axis a (radius ra) -> b (radius rb), no caps
};

struct Primitive {
  Shape shape = Shape::round_cone;
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  double ra = 0, rb = 0;
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Material material;
  bool human = false;  // counts towards the human mask (body, clothes, hair, hat)
};

// The DAVIS346 with its standard lens: the focal length in pixels the simulator renders
// with and `yelan run` assumes.
inline constexpr double kDavis346FocalPx = 485;

// Pinhole camera, no distortion. K in pixels, M world (mm) -> camera (mm).
struct CameraModel {
  int width = 346, height = 260;
  double fx = kDavis346FocalPx, fy = kDavis346FocalPx, cx = 173, cy = 130;
  Eigen::Matrix<double, 3, 4> M = Eigen::Matrix<double, 3, 4>::Zero();
  Eigen::Matrix3d K() const {
    Eigen::Matrix3d k;
    k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
    return k;
  }
};

// One rendered sample of the scene: linear intensity (photons-proportional, arbitrary but
// fixed units; lighting scales it), the human mask after occlusion, and depth (mm, camera z;
// +inf where nothing is hit). Row-major, width x height.
struct RenderedFrame {
  int width = 0, height = 0;
  std::vector<float> intensity;
  std::vector<std::uint8_t> mask;
  std::vector<float> depth_mm;
};

}  // namespace yelan::camera::sim
