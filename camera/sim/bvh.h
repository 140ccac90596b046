// BVH motion files (Biovision hierarchy): any hierarchy, any Euler channel order, position
// channels on any joint, End Sites. Read whole into memory (a clip is what a Motion plays),
// but with hard caps on frames and joints so a lying header cannot exhaust memory.
// Coordinates stay the file's own (BVH convention: Y up, the rest pose facing +Z, units of
// the file); the retargeting in motion.h converts to our world.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "camera/io/format_error.h"

namespace yelan::camera::sim {

// Bad BVH input: names the file, the byte offset and line of the problem and what was
// expected. A FormatError, so the CLI maps it to exit 2.
class BvhError : public FormatError {
 public:
  BvhError(const std::string& file, std::uint64_t offset, long line, const std::string& problem);
  long line() const { return line_; }

 private:
  long line_;
};

enum class BvhChannel : std::uint8_t { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

struct BvhJoint {
  std::string name;            // End Sites are named "<parent>/End Site"
  int parent = -1;             // index into BvhClip::joints; -1 for the root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // from the parent, in the parent's frame
  std::vector<BvhChannel> channels;  // in file order; rotations compose in this order
  int first_channel = 0;       // index of channels[0] within a frame's values
  bool end_site = false;       // an End Site: no channels, no children
};

struct BvhClip {
  std::string path;
  std::vector<BvhJoint> joints;  // parents before children (file order)
  int channel_count = 0;         // values per frame
  int frame_count = 0;
  double frame_time_s = 0;
  std::vector<double> values;    // frame-major: frame f starts at f * channel_count

  const double* frame(int f) const { return values.data() + std::size_t(f) * channel_count; }
  int find(const std::string& name) const;  // exact name; -1 when absent
};

// Throws BvhError on any malformed input (never crashes, never reads unbounded memory).
BvhClip read_bvh(const std::string& path);

// Joint j's local transform in frame f: translation = offset + its position channels,
// rotation = the product of its rotation channels in file order (R = R1 * R2 * R3 acting on
// column vectors, the usual BVH reading).
Eigen::Quaterniond bvh_local_rotation(const BvhClip& clip, int joint, int frame);
Eigen::Vector3d bvh_local_translation(const BvhClip& clip, int joint, int frame);

// Global (file frame) position and rotation of every joint from local rotations and
// translations (one per joint, as above). Parents precede children in `clip.joints`.
void bvh_forward_kinematics(const BvhClip& clip, const Eigen::Quaterniond* local_rot,
                            const Eigen::Vector3d* local_trans, Eigen::Vector3d* global_pos,
                            Eigen::Quaterniond* global_rot);

// Convenience: FK of frame f into the given vectors (resized to joints.size()).
void bvh_frame_pose(const BvhClip& clip, int frame, std::vector<Eigen::Vector3d>& global_pos,
                    std::vector<Eigen::Quaterniond>& global_rot);

// Rest pose (all channels zero): the global position of every joint.
std::vector<Eigen::Vector3d> bvh_rest_positions(const BvhClip& clip);

}  // namespace yelan::camera::sim
