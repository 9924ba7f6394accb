#pragma once
// The command line of sen3bot-sim lms200-emulator, parsed apart from running it so the
// options can be checked without a pty.
#include <cstdio>
#include <string>

#include "sen3bot/sim/lms200/emulator.hpp"

namespace sen3bot::sim {

struct Lms200EmulatorArgs {
  std::string pty_link;
  std::string map_path;  // empty: the built-in room
  bool have_pose = false;
  double pose[3] = {0, 0, 0};  // x (m), y (m), theta (rad)
  lms200::EmulatorOptions options;
};

// Fills `args` from the arguments after the command word. Returns 0, or 2 after printing
// what is wrong to `err`.
int parse_lms200_emulator_args(int argc, char** argv, Lms200EmulatorArgs& args, std::FILE* err);

}  // namespace sen3bot::sim
