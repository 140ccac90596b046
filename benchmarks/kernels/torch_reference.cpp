#include "benchmarks/kernels/torch_reference.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "benchmarks/bench_util.h"
#include "camera/io/temp_file.h"


#ifndef YELAN_SOURCE_DIR
#define YELAN_SOURCE_DIR "."
#endif

namespace yelan::bench {
namespace {

// The value after `"key": ` in one flat JSON object written by conv_bench.py.
std::string field(const std::string& obj, const std::string& key) {
  const std::string k = "\"" + key + "\": ";
  auto at = obj.find(k);
  if (at == std::string::npos) return {};
  at += k.size();
  if (obj[at] == '"') return obj.substr(at + 1, obj.find('"', at + 1) - at - 1);
  return obj.substr(at, obj.find_first_of(",}", at) - at);
}

}  // namespace

TorchTimes torch_conv_times(const std::vector<ConvCase>& cases, const std::vector<int>& threads, int reps,
                            std::string* why) {
  TorchTimes out;
  const char* env = std::getenv("YELAN_TORCH_SCRIPT");
  const std::string script = env ? env : YELAN_SOURCE_DIR "/benchmarks/torch/conv_bench.py";
  if (!reference_python_imports("torch")) {
    *why = "PyTorch is not importable by /usr/bin/python3 (apt-get install python3-torch)";
    return out;
  }
  std::ostringstream req;
  req << "{\"reps\": " << reps << ", \"threads\": [";
  for (std::size_t i = 0; i < threads.size(); ++i) req << (i ? ", " : "") << threads[i];
  req << "], \"cases\": [";
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const ConvCase& c = cases[i];
    const std::string kind = c.transposed ? "deconv2d" : "conv2d";
    req << (i ? ", " : "") << "{\"where\": \"" << c.where << "\", \"cin\": " << c.cin << ", \"cout\": " << c.cout
        << ", \"h\": " << c.h << ", \"w\": " << c.w << ", \"k\": " << c.k << ", \"stride\": " << c.stride
        << ", \"pad\": " << c.pad << ", \"transposed\": " << (c.transposed ? "true" : "false")
        << ", \"out_pad_h\": " << c.out_pad_h << ", \"out_pad_w\": " << c.out_pad_w << ", \"ops\": [\"" << kind
        << ".fwd\", \"" << kind << ".bwd_data\", \"" << kind << ".bwd_weights\"]}";
  }
  req << "]}";
  // The request in a file of ours, created exclusively under a random name (a fixed name in
  // /tmp could be a planted link), removed when `request` goes.
  const camera::TempFile request((std::filesystem::temp_directory_path() / "yelan-torch-request.json").string());
  std::ofstream(request.path()) << req.str();
  Program py({"/usr/bin/python3", script});
  py.stdin_path = request.path();
  py.capture_stdout = true;
  py.show_stderr = true;
  const ProgramResult res = run_program(py);
  const std::string text = res.ok() ? res.out : std::string();
  if (text.empty()) {
    *why = "the PyTorch script failed: /usr/bin/python3 " + script + ": " + (res.ok() ? "no output" : res.why());
    return out;
  }
  for (std::size_t at = text.find('{'); at != std::string::npos; at = text.find('{', at + 1)) {
    const std::string obj = text.substr(at, text.find('}', at) - at + 1);
    out[{field(obj, "where"), field(obj, "op"), std::atoi(field(obj, "threads").c_str())}] =
        std::atof(field(obj, "ms").c_str());
  }
  return out;
}

}  // namespace yelan::bench
