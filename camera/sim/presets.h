// Named simulations. A preset name is `<character>-<motion>-<view>-<light>-<bg>` (a member of
// the paper's grid, e.g. `ana-05_04-front-high-static`) or its short form
// `<view>-<light>-<bg>` (default character and motion, e.g. `front-low-dynamic`); either may
// end in `-occluded` (static and moving occluders), `-flicker` (mains flicker) and/or
// `-empty` (nobody there: the scene alone, for stage 1's negatives).
// motion: a CMU clip stem (05_04, ...), `dance` (style from the seed) or `dance<N>`.
// view: front|back|left|right; light: high|medium|low; bg: static|dynamic.
// A scene.json gives the same fields by name, plus camera, pixel and timing settings.
#pragma once
#include <string>
#include <vector>

#include "camera/sim/simulator.h"

namespace yelan::camera::sim {

SimSpec preset_spec(const std::string& name);
// Fields of a JSON object (see camera/sim/README.md); `what` names the source in errors.
SimSpec spec_from_json(const std::string& text, const std::string& what);

// The CMU clips of each split (../shared/data/mocap/README.md), by stem.
const std::vector<std::string>& train_motions();
const std::vector<std::string>& test_motions();

// The grid's members: characters x motions x 4 views x 3 lights x 2 backgrounds, for the
// "train" split (training characters, train clips and `dance`), "test" (held-out
// characters, test clips and `dance`) or "all". Empty filters keep everything.
struct GridFilter {
  std::vector<std::string> characters, motions, views, lights, backgrounds;
};
std::vector<std::string> grid_presets(const std::string& split, const GridFilter& filter = {});

}  // namespace yelan::camera::sim
