#pragma once
#include <cstdio>

namespace sen3bot::firmware {

// The whole command line: `sen3bot --help`, `sen3bot version`, `sen3bot run --config FILE`,
// `sen3bot capture dump FILE`. Returns the process exit code.
int cli_main(int argc, char** argv, std::FILE* out, std::FILE* err);

}  // namespace sen3bot::firmware
