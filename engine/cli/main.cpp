#include <iostream>

#include "engine/cli/cli.h"

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  return yelan::cli::run(args, std::cout, std::cerr);
}
