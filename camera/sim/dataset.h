// A dataset made once and reused: train / val / test recordings of whole clips with
// augmentation drawn per recording (mirrored motion, speed, start anywhere in the clip, yaw /
// distance / height jitter around the four views, body and clothes varied, lighting,
// backgrounds, flicker, occluders). The splits never share a body or a stretch of motion:
//   train: the training characters but two, the first 85% of each training clip, dances;
//   val:   the two held-out training characters, the last 15% of each training clip,
//          dances of other styles;
//   test:  the test characters and clips (../shared/data/mocap/README.md), dances;
// and, per split, scenes with nobody in them (stage 1's negatives).
// Member i of a split is a pure function of (seed, split, i): the same command makes the
// same bytes, done files are kept, so an interrupted run resumes where it stopped.
#pragma once
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "camera/sim/simulator.h"

namespace yelan::camera::sim {

struct DatasetSpec {
  std::string out_dir;        // out_dir/{train,val,test}/*.yelan.h5 and out_dir/manifest.json
  std::uint64_t seed = 1;
  int train = 400, val = 40, test = 60;
  // Scenes with nobody in them per split (named <split>-empty-NNNNN-...): rooms, moving
  // backgrounds, flickering lamps, occluders and sensor noise at every lighting, drawn from
  // their own seed stream (adding them never changes the dancer members).
  int train_empty = 0, val_empty = 0, test_empty = 0;
  // Furnished rooms with nobody in them (<split>-room-NNNNN-...-clutter[-pan|-shake|-sweep]),
  // most of them filmed by a hand-held camera looking around: what a real room in front of a
  // moving event camera looks like (the empty scenes above are bare walls). Own seed stream.
  int train_rooms = 0, val_rooms = 0, test_rooms = 0;
  // Dancers in furnished rooms (<split>-dancer-room-NNNNN-...-clutter[-pan|-shake|-sweep]):
  // stage 1 must find the dancer among the furniture, not only tell a room from a dancer.
  // Drawn as the dancer members are (cast, segments, looks, framing), from their own stream.
  int train_dancer_rooms = 0, val_dancer_rooms = 0, test_dancer_rooms = 0;
  double duration_s = 5;
  // Training recordings each get new looks (random_looks: body, garment, hair, every
  // material) instead of a cast member's; validation and test keep their held-out cast.
  bool random_looks = false;
  // Every dancer recording frames its dancer (SimSpec::frame_dancer): without it, a clip
  // started anywhere leaves a quarter of the joints out of the picture.
  bool frame_dancer = false;
  // When set, the lamp's level in DN of every low-light member (dancer and empty) instead of
  // the simulator's (SceneConfig::light_dn): 4 makes ds-s1 and ds-s2, drawn before low light
  // was raised to 20 DN.
  std::optional<double> low_light_dn;
  // The share of training dancers (plain and in furnished rooms) whose arms play their clip
  // 0.25-3 s after the body, each arm its own offset (SimSpec::arm_offset_s; named
  // ...-remix): arm and body poses the 13 training clips never had together. Drawn from its
  // own stream, so every other member keeps its bytes; validation and test are never remixed.
  double remix_arms = 0;
  // The share of training dancers (plain and in furnished rooms) whose arms leave their
  // motion for key poses drawn anywhere in the arm's range (SimSpec::free_arms_seed; named
  // ...-free): arm poses no clip has, on the clips' bodies. Own stream, as remix_arms; a
  // member drawn for both is remixed, not freed. Validation and test are never touched.
  double free_arms = 0;
  // Scale of every dancer's front cues (SimSpec::front_print; 1 as drawn, 0 none, up to 3):
  // how strongly the events tell a dancer's front from the back. Not in the files' names:
  // a dataset is only added to at the scale its manifest names.
  double front_print = 1;
  // Above front_print: each dancer recording (every split) draws its own scale uniformly in
  // [front_print, front_print_max] from its own stream, so a net learns the cue at every
  // strength and no split depends on one outfit (scene.json names the drawn scale).
  double front_print_max = 1;
  // Only the members whose scene matches one of these conditions are made (none: every
  // member): each is a set of scene words joined by '-' ("low-sweep", "flicker"), all of them
  // among the words of the member's scene (its name after motion: view, light, background,
  // occluded, flicker, clutter, camera motion). The counts above are the members drawn, the
  // kept ones keep their index and bytes: a stage-1 fine-tune on what fails, drawn as always.
  std::vector<std::string> only;
  int threads = 0;            // recordings simulated at once; 0: all cores
  bool progress_tty = false;  // a live line (else a line per recording)
};

// The characters each split draws from.
const std::vector<std::string>& dataset_characters(const std::string& split);

// Member i of a split: the scene, motion and augmentation, and its file name.
// random_looks, frame_dancer: as DatasetSpec's (looks change only the training split's
// looks and names; framing changes no draw, only where the motion is placed).
SimSpec dataset_member(const std::string& split, int i, std::uint64_t seed, double duration_s,
                       bool random_looks = false, bool frame_dancer = false);
SimSpec dataset_empty_member(const std::string& split, int i, std::uint64_t seed, double duration_s);
SimSpec dataset_room_member(const std::string& split, int i, std::uint64_t seed, double duration_s);
SimSpec dataset_dancer_room_member(const std::string& split, int i, std::uint64_t seed, double duration_s,
                                   bool random_looks = false, bool frame_dancer = false);
std::string dataset_file_name(const SimSpec& spec);
// The words of a member's scene ("front", "low", "static", "flicker", "sweep", ...).
std::vector<std::string> scene_words(const SimSpec& spec);
// Every word a scene's name may hold (scene_words' vocabulary; "still" stands for a still
// camera, which the name leaves out).
const std::vector<std::string>& scene_vocabulary();
// Whether a member with these scene words is kept under DatasetSpec::only (empty: always).
// Throws std::invalid_argument on a condition with an unknown or empty word.
bool scene_matches(const std::vector<std::string>& words, const std::vector<std::string>& only);
// Training dancer i of a dataset of `seed` with share p of remixed arms: sets its arm
// offsets and appends "-remix" to its name when the draw says so (room: a dancer-room member).
void remix_member_arms(SimSpec& spec, std::uint64_t seed, int i, bool room, double p);
// The same for free arms: sets SimSpec::free_arms_seed and appends "-free" when the draw says
// so and the member's arms are not remixed.
void free_member_arms(SimSpec& spec, std::uint64_t seed, int i, bool room, double p);

// The front print's scale of a member (DatasetSpec::front_print..front_print_max): lo where
// the range is empty or nobody dances, else drawn from the member's split and name.
double member_front_print(const std::string& split, const SimSpec& spec, std::uint64_t seed, double lo, double hi);

// Simulates what is missing, in parallel, and writes the manifest (every member's scene as
// JSON, split, file). Returns the number of recordings simulated now.
int make_dataset(const DatasetSpec& spec, std::ostream& err);

}  // namespace yelan::camera::sim
