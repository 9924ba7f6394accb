#pragma once
// Running a command's entry point in-process, as its binary would, with what it prints caught.
#include <cstdio>
#include <string>
#include <vector>

namespace sen3bot::testing {

// Everything written to a temporary file so far.
inline std::string read_all(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string text;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
  return text;
}

struct CommandOutcome {
  int code = -1;
  std::string out;
  std::string err;
};

// int command(int argc, char** argv, FILE* out, FILE* err), given the arguments after its words.
template <typename Command>
CommandOutcome run_command(Command command, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  CommandOutcome o;
  o.code = command(static_cast<int>(argv.size()), argv.data(), out, err);
  o.out = read_all(out);
  o.err = read_all(err);
  std::fclose(out);
  std::fclose(err);
  return o;
}

}  // namespace sen3bot::testing
