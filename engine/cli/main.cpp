#include <iostream>

#include "camera/io/temp_file.h"
#include "engine/cli/cli.h"

int main(int argc, char** argv) {
  // Ctrl-C or SIGTERM leaves no temporary file behind (commands that must finish their work
  // on a signal, such as a live run, install their own handlers on top).
  yelan::camera::remove_temp_files_on_signal();
  std::vector<std::string> args(argv + 1, argv + argc);
  return yelan::cli::run(args, std::cout, std::cerr);
}
