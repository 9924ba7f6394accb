#pragma once
// Running `sen3bot-sim experiment` in-process for the tests, and reading what it wrote.
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "text_file.hpp"
#include "command_capture.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim::testing {

inline const std::string kConfig = SEN3BOT_SOURCE_DIR "/config/dol_arena.yaml";

using sen3bot::testing::read_file;

using sen3bot::testing::read_all;
using CommandRun = sen3bot::testing::CommandOutcome;

inline CommandRun run_experiment(std::vector<std::string> args) {
  return sen3bot::testing::run_command(experiment_command, std::move(args));
}

// The command refuses `args` as a usage error: exit 2, one line on stderr that contains
// `says`, nothing on stdout.
inline void expect_usage_error(const std::vector<std::string>& args, const std::string& says) {
  const CommandRun run = run_experiment(args);
  std::string line;
  for (const std::string& a : args) line += a + " ";
  EXPECT_EQ(run.code, 2) << line;
  EXPECT_NE(run.err.find(says), std::string::npos) << line << "\n" << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << line << "\n" << run.err;
  EXPECT_EQ(run.out, "") << line;
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
