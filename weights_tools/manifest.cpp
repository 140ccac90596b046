#include "weights_tools/manifest.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "weights_tools/parse_json.h"

namespace yelan::weights {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void bad(const std::string& path, const std::string& problem) {
  throw WeightsError(path + ": " + problem);
}

// Manifests are small (~150 kB for the paper config); anything huge is not one.
constexpr std::uintmax_t kMaxManifestBytes = 64u << 20;
constexpr std::size_t kListedNames = 20;
constexpr std::size_t kListedShapes = 10;

std::string read_text(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) bad(path, "no such file");
  if (fs::file_size(path, ec) > kMaxManifestBytes) bad(path, "too large for a manifest");
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A name such as "small" or "small-pose0.125", not a path or a file name.
bool is_config_name(const std::string& s) {
  if (s.empty() || s.ends_with(".json")) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

}  // namespace

std::string config_dir() {
  if (const char* env = std::getenv("YELAN_CONFIG_DIR"); env && *env) return env;
#ifdef YELAN_WEIGHTS_CONFIG_DIR
  return YELAN_WEIGHTS_CONFIG_DIR;
#else
  return "weights_tools/configs";
#endif
}

Manifest read_manifest(const std::string& path) {
  using Json = nlohmann::ordered_json;
  Json doc;
  try {
    doc = parse_json(read_text(path));
  } catch (const JsonError& e) {
    bad(path, std::string("not valid JSON: ") + e.what());
  }
  // The member `key` of an object; nullptr when absent or when `o` is not an object.
  auto find = [](const Json& o, const char* key) -> const Json* {
    const auto it = o.find(key);
    return it == o.end() ? nullptr : &*it;
  };
  const Json* format = find(doc, "format");
  if (!format || *format != "yelan-weights-manifest")
    bad(path, "not a weights manifest (format is not 'yelan-weights-manifest')");
  const Json* version = find(doc, "version");
  if (!version || !version->is_number() || *version != 1) bad(path, "manifest version is not 1");
  const Json* config = find(doc, "config");
  if (!config || !config->is_object()) bad(path, "manifest has no config object");
  Manifest m;
  m.path = path;
  m.config_json = config->dump();
  if (const Json* name = find(*config, "name"); name && name->is_string()) m.config_name = name->get<std::string>();
  const Json* groups = find(doc, "groups");
  if (!groups || !groups->is_object()) bad(path, "manifest has no groups object");
  for (const std::string& g : group_names()) {
    const Json* list = find(*groups, g.c_str());
    if (!list || !list->is_array()) bad(path, "manifest has no list for group '" + g + "'");
    auto& out = m.groups[g];
    for (std::size_t i = 0; i < list->size(); ++i) {
      const Json& t = (*list)[i];
      const std::string where = "groups." + g + "[" + std::to_string(i) + "]";
      const Json* name = find(t, "name");
      const Json* shape = find(t, "shape");
      if (!name || !name->is_string() || !shape || !shape->is_array())
        bad(path, where + " needs a string 'name' and an array 'shape'");
      const std::string n = name->get<std::string>();
      Shape s;
      for (const Json& d : *shape) {
        const double v = d.is_number() ? d.get<double>() : -1;
        if (v < 0 || v > double(kMaxElements) || v != std::floor(v))
          bad(path, where + " (" + n + "): shape holds a non-integer or absurd size");
        s.push_back(static_cast<std::int64_t>(v));
      }
      if (!out.emplace(n, std::move(s)).second) bad(path, where + ": '" + n + "' listed twice");
    }
  }
  return m;
}

Manifest find_manifest(const std::string& name_or_path) {
  std::error_code ec;
  if (is_config_name(name_or_path) && !fs::exists(name_or_path, ec)) {
    const std::string p = (fs::path(config_dir()) / (name_or_path + ".manifest.json")).string();
    if (!fs::exists(p, ec))
      throw WeightsError("no config named '" + name_or_path + "' (" + p +
                         " does not exist; weights_tools/make_manifest.py writes it)");
    return read_manifest(p);
  }
  const std::string& p = name_or_path;
  if (!fs::exists(p, ec)) throw WeightsError(p + ": no such file");
  const std::string suffix = ".manifest.json";
  if (p.size() > suffix.size() && p.compare(p.size() - suffix.size(), suffix.size(), suffix) == 0)
    return read_manifest(p);
  // A config file: its manifest sits beside it.
  fs::path beside = fs::path(p);
  beside.replace_extension(".manifest.json");
  // Else the manifest make_manifest.py wrote for the config's stem in the config folder.
  const fs::path named = fs::path(config_dir()) / (fs::path(p).stem().string() + ".manifest.json");
  if (!fs::exists(beside, ec) && fs::exists(named, ec)) return read_manifest(named.string());
  if (!fs::exists(beside, ec))
    throw WeightsError(p + ": a config without a manifest (expected " + beside.string() +
                       "; run weights_tools/make_manifest.py " + p + ")");
  return read_manifest(beside.string());
}

std::vector<std::string> compare_with_manifest(const WeightsReader& file, const Manifest& m) {
  std::vector<std::string> lines;
  // A file of another config differs in hundreds of tensors: the first few say enough.
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    for (std::size_t i = 0; i < v.size() && i < kListedNames; ++i) s.append(i ? ", " : "").append(v[i]);
    if (v.size() > kListedNames) s.append(", ... (" + std::to_string(v.size() - kListedNames) + " more)");
    return s;
  };
  for (const std::string& g : group_names()) {
    const std::string where = file.path() + " (" + g + ")";
    const auto& want = m.groups.at(g);
    std::set<std::string> have;
    std::vector<std::string> unexpected, misshaped;
    for (const TensorInfo& t : file.tensors(g)) {
      have.insert(t.name);
      auto it = want.find(t.name);
      if (it == want.end()) unexpected.push_back(t.name);
      else if (it->second != t.shape)
        misshaped.push_back(where + ": " + t.name + ": shape " + shape_text(t.shape) + ", expected " +
                            shape_text(it->second));
    }
    std::vector<std::string> missing;
    for (const auto& [name, shape] : want)
      if (!have.count(name)) missing.push_back(name);
    if (!missing.empty()) lines.push_back(where + ": " + std::to_string(missing.size()) + " missing: " + list(missing));
    if (!unexpected.empty())
      lines.push_back(where + ": " + std::to_string(unexpected.size()) + " unexpected: " + list(unexpected));
    for (std::size_t i = 0; i < misshaped.size() && i < kListedShapes; ++i) lines.push_back(misshaped[i]);
    if (misshaped.size() > kListedShapes)
      lines.push_back(where + ": " + std::to_string(misshaped.size() - kListedShapes) +
                      " more tensors with a wrong shape");
  }
  return lines;
}

void verify(const WeightsReader& file, const Manifest& m) {
  const auto lines = compare_with_manifest(file, m);
  if (lines.empty()) return;
  std::string msg = file.path() + ": does not match config '" + m.config_name + "' (" + m.path + ")";
  for (const std::string& line : lines) msg.append("\n").append(line);
  throw WeightsError(msg);
}

}  // namespace yelan::weights
