// sen3bot-sim: the firmware on the simulated robot, the scenarios, and the device emulators.
#include <cstdio>

#include "sim_commands.hpp"

int main(int argc, char** argv) { return sen3bot::sim::sim_cli_main(argc, argv, stdout, stderr); }
