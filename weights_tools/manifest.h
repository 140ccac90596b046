// Manifests: the names and shapes a config's weights file must hold, generated per config
// by weights_tools/make_manifest.py (configs/<name>.manifest.json), so that weights can be
// verified here without building the networks.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "weights_tools/weights_file.h"

namespace yelan::weights {

struct Manifest {
  std::string path;         // where it was read from
  std::string config_name;  // config.name
  std::string config_json;  // compact
  std::map<std::string, std::map<std::string, Shape>> groups;
};

// weights_tools/configs of the source tree, or $YELAN_CONFIG_DIR when set.
std::string config_dir();

Manifest read_manifest(const std::string& path);
// NAME -> <config_dir>/NAME.manifest.json. A path -> that manifest, or for a config file
// X.json the X.manifest.json beside it.
Manifest find_manifest(const std::string& name_or_path);

// One line per difference: "FILE (pose): 2 missing: a, b", "... 1 unexpected: c",
// "FILE (pose): key: shape [1, 2], expected [2, 1]". Empty when the file matches.
std::vector<std::string> compare_with_manifest(const WeightsReader& file, const Manifest& m);
// Throws WeightsError holding every line of compare_with_manifest.
void verify(const WeightsReader& file, const Manifest& m);

}  // namespace yelan::weights
