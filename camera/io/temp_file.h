// The one way yelan writes a file: into a temporary file beside the target, renamed over it
// when complete, so a crash, an error or Ctrl-C never leaves a half-written file under the
// real name. The temporary file is created exclusively (O_CREAT | O_EXCL with a random part
// in its name, as mkstemp does) with the permissions an ordinary file gets, so a link planted
// at a predictable name is never followed or overwritten. Live temporary files are listed in
// a signal-safe registry: remove_temp_files() (async-signal-safe) deletes them, and
// remove_temp_files_on_signal() installs SIGINT/SIGTERM handlers that do so and then die by
// the signal as before.
#pragma once
#include <string>

namespace yelan::camera {

class TempFile {
 public:
  explicit TempFile(std::string final_path);  // throws std::runtime_error naming the path
  ~TempFile();                                 // removes the temporary file unless committed
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return temp_; }
  const std::string& final_path() const { return final_; }
  // Renames the temporary file over the final path; throws std::runtime_error on failure.
  void commit();

 private:
  std::string final_, temp_;
  int slot_ = -1;
  bool committed_ = false;
};

// `text` written to `path` through a TempFile; throws std::runtime_error naming the file.
void write_file_atomically(const std::string& path, const std::string& text);

// Deletes every live temporary file (async-signal-safe: unlink only).
void remove_temp_files();
// SIGINT and SIGTERM remove the live temporary files, then the process dies by the signal.
void remove_temp_files_on_signal();

}  // namespace yelan::camera
