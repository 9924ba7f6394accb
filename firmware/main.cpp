// sen3bot: the robot firmware's command-line entry point.
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#include "cli.hpp"

int main(int argc, char** argv) { return sen3bot::firmware::cli_main(argc, argv, stdout, stderr); }
