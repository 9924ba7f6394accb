// `sen3bot recognize` on a small checked-in paths file (held-out workers, one or two per
// operation) with the shipped model and operations.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "command_capture.hpp"
#include "commands.hpp"

namespace sen3bot::firmware {
namespace {

const std::string kPaths = SEN3BOT_SOURCE_DIR "/tests/data/cobot/paths.jsonl";
const std::string kOperations = SEN3BOT_SOURCE_DIR "/config/cobot/operations.yaml";
const std::string kModel = SEN3BOT_SOURCE_DIR "/config/cobot/operations-model.yaml.gz";

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::size_t lines_in(const std::string& path) {
  std::ifstream f(path);
  std::size_t n = 0;
  for (std::string line; std::getline(f, line);) n += !line.empty();
  return n;
}

TEST(RecognizeCommand, RecognisesTheCheckedInPaths) {
  const testing::CommandOutcome o = testing::run_command(
      recognize_command, {"--paths", kPaths, "--model", kModel, "--operations", kOperations});
  ASSERT_EQ(o.code, 0) << o.err;
  const std::size_t paths = lines_in(kPaths);
  ASSERT_GE(paths, 5u);
  EXPECT_EQ(count(o.out, "(right)"), paths) << o.out;
  EXPECT_EQ(count(o.out, "(WRONG)"), 0u) << o.out;
  EXPECT_NE(o.out.find(std::to_string(paths) + " of " + std::to_string(paths) + " paths recognised (accuracy 1.000)"),
            std::string::npos)
      << o.out;
  // Each path's line lists every operation's probability.
  EXPECT_EQ(count(o.out, "\n  kitting "), paths) << o.out;
  EXPECT_EQ(count(o.out, "walked"), 0u);
}

TEST(RecognizeCommand, ProgressiveTable) {
  const testing::CommandOutcome o = testing::run_command(
      recognize_command, {"--paths", kPaths, "--progressive", "--model", kModel, "--operations", kOperations});
  ASSERT_EQ(o.code, 0) << o.err;
  const std::size_t paths = lines_in(kPaths);
  EXPECT_EQ(count(o.out, "  walked"), paths);
  EXPECT_EQ(count(o.out, "  P(right)"), paths);
  EXPECT_EQ(count(o.out, "100%\n"), paths);
  EXPECT_NE(o.out.find("mean P(right) at 10%: "), std::string::npos) << o.out;
}

std::string write_temp(const std::string& text) {
  const std::string path = "/tmp/sen3bot-recognize-" + std::to_string(::getpid()) + ".jsonl";
  std::ofstream(path) << text;
  return path;
}

TEST(RecognizeCommand, BadInput) {
  const std::string bad = write_temp("{\"points\": [[1, 2], [1.5, 2]]}\n{\"points\": [[1, 2]]\n");
  testing::CommandOutcome o =
      testing::run_command(recognize_command, {"--paths", bad, "--model", kModel, "--operations", kOperations});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find(bad + ": line 2: "), std::string::npos) << o.err;

  const std::string unknown = write_temp("{\"operation\": \"juggling\", \"points\": [[1, 2]]}\n");
  o = testing::run_command(recognize_command, {"--paths", unknown, "--model", kModel, "--operations", kOperations});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("no operation named 'juggling'"), std::string::npos) << o.err;
  ::unlink(unknown.c_str());

  o = testing::run_command(recognize_command, {"--model", kModel});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--paths is required"), std::string::npos) << o.err;
  o = testing::run_command(recognize_command, {"--paths", kPaths, "--model", "/nonexistent.yaml.gz", "--operations", kOperations});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("/nonexistent.yaml.gz"), std::string::npos) << o.err;
  o = testing::run_command(recognize_command, {"--paths", kPaths, "--frobnicate", "1"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("unknown option '--frobnicate'"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace sen3bot::firmware
