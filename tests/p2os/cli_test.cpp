// The Pioneer command-line tools: decode p2os on the checked-in capture, drive against the
// emulator over TCP, and argument errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "sim_commands.hpp"
#include "sen3bot/sim/p2os/emulator_runner.hpp"

namespace sen3bot::firmware {
namespace {

// Runs a command with argv built from `args`; returns (exit code, stdout, stderr).
struct Outcome {
  int rc;
  std::string out;
  std::string err;
};

template <typename F>
Outcome run(F command, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  const int rc = command(static_cast<int>(argv.size()), argv.data(), out, err);
  auto slurp = [](std::FILE* f) {
    std::string text;
    std::rewind(f);
    char buffer[4096];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) text.append(buffer, n);
    std::fclose(f);
    return text;
  };
  return {rc, slurp(out), slurp(err)};
}

TEST(P2osCli, DecodePrintsTheCheckedInLines) {
  const std::string dir = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/";
  const Outcome o = run(decode_p2os_command, {dir + "p2os_session.s3bcap"});
  EXPECT_EQ(o.rc, 0) << o.err;
  std::ifstream in(dir + "p2os_session.jsonl");
  std::stringstream expected;
  expected << in.rdbuf();
  EXPECT_EQ(o.out, expected.str());
}

TEST(P2osCli, DecodeErrors) {
  EXPECT_EQ(run(decode_p2os_command, {}).rc, 2);
  const Outcome missing = run(decode_p2os_command, {"/nonexistent/file.s3bcap"});
  EXPECT_EQ(missing.rc, 1);
  EXPECT_NE(missing.err.find("sen3bot decode p2os"), std::string::npos);
}

TEST(P2osCli, DriveAgainstTheEmulatorOverTcp) {
  auto runner = p2os::TcpEmulatorRunner::start(p2os::EmulatorConfig{}, 0);
  ASSERT_TRUE(runner) << runner.error().c_str();
  const std::string port = "tcp://127.0.0.1:" + std::to_string((*runner)->port());
  const Outcome o = run(drive_command, {"--port", port, "--vel", "0.2", "--rvel", "0", "--seconds", "0.8"});
  EXPECT_EQ(o.rc, 0) << o.err;
  EXPECT_NE(o.out.find("\"x_m\":"), std::string::npos);
  EXPECT_NE(o.out.find("\"battery_v\":13.0"), std::string::npos);
  // Closed cleanly: the emulator went back to waiting for a handshake.
  bool closed = false;
  for (int i = 0; i < 100 && !closed; ++i) {
    closed = (*runner)->with_emulator([](p2os::P2osEmulator& e) {
      return e.state() == p2os::EmulatorState::sync_wait && e.stats().sessions_opened == 1;
    });
    if (!closed) hal::PosixClock().sleep_until(hal::PosixClock().now() + hal::millis(10));
  }
  EXPECT_TRUE(closed);
}

TEST(P2osCli, ArgumentErrors) {
  EXPECT_EQ(run(drive_command, {"--vel", "0.1"}).rc, 2);
  EXPECT_EQ(run(drive_command, {"--port", "tcp://127.0.0.1:1", "--vel", "abc", "--seconds", "1"}).rc, 2);
  EXPECT_EQ(run(drive_command, {"--port", "tcp://127.0.0.1:1", "--vel", "0", "--rvel", "0", "--seconds", "1"}).rc, 1);
  EXPECT_EQ(run(sim::p2os_emulator_command, {}).rc, 2);
  EXPECT_EQ(run(sim::p2os_emulator_command, {"--tcp", "70000"}).rc, 2);
  EXPECT_EQ(run(sim::p2os_emulator_command, {"--pty", "/tmp/x", "--tcp", "1"}).rc, 2);
  const Outcome bad_watchdog = run(sim::p2os_emulator_command, {"--tcp", "0", "--watchdog", "resum"});
  EXPECT_EQ(bad_watchdog.rc, 2);
  EXPECT_NE(bad_watchdog.err.find("expected 'stop' or 'resume', got 'resum'"), std::string::npos) << bad_watchdog.err;
}

}  // namespace
}  // namespace sen3bot::firmware
