#pragma once
// Running `sen3bot-sim experiment` in-process for the tests, and reading what it wrote.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sim_commands.hpp"

namespace sen3bot::sim::testing {

inline const std::string kConfig = SEN3BOT_SOURCE_DIR "/config/dol_arena.yaml";

inline std::string read_file(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

inline std::string read_all(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string text;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
  return text;
}

struct CommandRun {
  int code = -1;
  std::string out;
  std::string err;
};

inline CommandRun run_experiment(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  CommandRun run;
  run.code = experiment_command(static_cast<int>(argv.size()), argv.data(), out, err);
  run.out = read_all(out);
  run.err = read_all(err);
  std::fclose(out);
  std::fclose(err);
  return run;
}

inline std::string temp_dir() {
  char dir[] = "/tmp/sen3bot-experiment-XXXXXX";
  return ::mkdtemp(dir) != nullptr ? dir : "";
}

// `"name": {"count": N` in a variant's part of report.json.
inline long count(const std::string& json, const std::string& name) {
  const std::size_t at = json.find("\"" + name + "\": {\"count\": ");
  if (at == std::string::npos) return -1;
  return std::strtol(json.c_str() + at + name.size() + 14, nullptr, 10);
}

inline long file_size(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<long>(st.st_size) : -1;
}

}  // namespace sen3bot::sim::testing
