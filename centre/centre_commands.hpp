#pragma once
// The fleet centre's commands; centre_cli.cpp dispatches to them. Each takes the arguments
// after its command word and returns the exit status (0 success, 1 run-time failure, 2 bad
// command line).
#include <cstdio>

namespace sen3bot::centre {

// The whole command line of sen3bot-centre.
int centre_cli_main(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-centre ssc --broker URL --site SITE.yaml [--username U --password-file F --ca-file F]
//   [--event-log FILE] [--duration S] [--client-id ID]
int ssc_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-centre formation --broker URL --example 1|2|3 --team SERIAL,... [...] (cmd_formation.cpp)
int formation_command(int argc, char** argv, std::FILE* out, std::FILE* err);

}  // namespace sen3bot::centre
