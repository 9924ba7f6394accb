// The LMS200 command-line tools: decode lms200 reproduces the checked-in JSON lines, scan
// talks to the emulator on a pty, and bad command lines are refused with status 2.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "sim_commands.hpp"
#include "rig.hpp"
#include "sen3bot/sim/lms200/pty_runner.hpp"

namespace sen3bot::lms200 {
namespace {

struct CliRun {
  int status = 0;
  std::string out;
  std::string err;
};

CliRun run_cli(std::vector<std::string> args) {
  args.insert(args.begin(), "sen3bot");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  char* out_buffer = nullptr;
  char* err_buffer = nullptr;
  std::size_t out_size = 0;
  std::size_t err_size = 0;
  std::FILE* out = open_memstream(&out_buffer, &out_size);
  std::FILE* err = open_memstream(&err_buffer, &err_size);
  CliRun r;
  // The emulator is the simulator's command; the rest are the robot's.
  const bool simulator = args.size() > 1 && args[1] == "lms200-emulator";
  r.status = simulator ? sim::sim_cli_main(static_cast<int>(argv.size()), argv.data(), out, err)
                       : firmware::cli_main(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  r.out.assign(out_buffer, out_size);
  r.err.assign(err_buffer, err_size);
  std::free(out_buffer);
  std::free(err_buffer);
  return r;
}

TEST(Lms200Cli, DecodeMatchesCheckedInJson) {
  const std::string dir = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/";
  const CliRun r = run_cli({"decode", "lms200", dir + "lms200_session.s3bcap"});
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(dir + "lms200_session.jsonl");
  std::stringstream want;
  want << in.rdbuf();
  EXPECT_EQ(r.out, want.str());
  EXPECT_NE(r.err.find("scans"), std::string::npos);
}

TEST(Lms200Cli, ScanPrintsJsonLinesFromTheEmulator) {
  WallWorld world = testing::test_world();
  Result<std::unique_ptr<Lms200PtyRunner>> runner = Lms200PtyRunner::open(EmulatorOptions{}, world);
  ASSERT_TRUE(runner.ok());
  (*runner)->start();
  const CliRun r = run_cli({"scan", "--port", std::string((*runner)->slave_path()), "--baud", "38400", "--variant",
                         "100/1", "--units", "cm", "--count", "2", "--timeout", "40"});
  ASSERT_EQ(r.status, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    EXPECT_NE(line.find("\"units\":\"cm\""), std::string::npos);
    EXPECT_NE(line.find("\"baud\":38400"), std::string::npos);
    EXPECT_NE(line.find("\"count\":101"), std::string::npos);
    EXPECT_NE(line.find("\"ranges_m\":[3.920,"), std::string::npos) << line.substr(0, 200);
  }
  EXPECT_EQ(n, 2);
  // The clean stop left the scanner at 9600, out of streaming mode.
  (*runner)->with_emulator([](Lms200Emulator& e) {
    EXPECT_EQ(e.baud(), 9600u);
    EXPECT_FALSE(e.streaming());
  });
}

TEST(Lms200Cli, BadCommandLinesAreRefused) {
  EXPECT_EQ(run_cli({"scan", "--baud", "38400"}).status, 2);
  EXPECT_EQ(run_cli({"scan", "--port", "/dev/null", "--variant", "180/0.25"}).status, 2);
  EXPECT_EQ(run_cli({"scan", "--port", "/dev/null", "--baud", "115200"}).status, 2);
  EXPECT_EQ(run_cli({"lms200-emulator", "--status", "0x10"}).status, 2);
  EXPECT_EQ(run_cli({"lms200-emulator", "--pty", "/tmp/x", "--pose", "1,2"}).status, 2);
  EXPECT_EQ(run_cli({"decode", "lms200"}).status, 2);
  EXPECT_EQ(run_cli({"decode", "lms200", "/nonexistent.s3bcap"}).status, 1);
}

}  // namespace
}  // namespace sen3bot::lms200
