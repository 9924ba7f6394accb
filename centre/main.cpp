// sen3bot-centre: the fleet centre's command-line entry point.
#include <cstdio>

#include "centre_commands.hpp"

int main(int argc, char** argv) { return sen3bot::centre::centre_cli_main(argc, argv, stdout, stderr); }
