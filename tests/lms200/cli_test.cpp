// The LMS200 command-line tools: decode lms200 reproduces the checked-in JSON lines, scan
// talks to the emulator on a pty, the emulator's options reach the emulator, a fault given on
// its command line is seen by the driver, and bad command lines are refused with status 2.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "lms200_emulator_options.hpp"
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
    EXPECT_NE(line.find("\"status\":\"0x10\",\"device_status\":0,\"fault\":false"), std::string::npos);
    EXPECT_NE(line.find("\"status\":\"0x10\",\"device_status\":0,\"fault\":false"), std::string::npos);
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

struct Parsed {
  int status = 0;
  sim::Lms200EmulatorArgs args;
  std::string err;
};

Parsed parse_emulator(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  char* err_buffer = nullptr;
  std::size_t err_size = 0;
  std::FILE* err = open_memstream(&err_buffer, &err_size);
  Parsed p;
  p.status = sim::parse_lms200_emulator_args(static_cast<int>(argv.size()), argv.data(), p.args, err);
  std::fclose(err);
  p.err.assign(err_buffer, err_size);
  std::free(err_buffer);
  return p;
}

TEST(Lms200EmulatorOptions, DefaultsAreThoseOfTheLibrary) {
  const Parsed p = parse_emulator({"--pty", "/tmp/lms"});
  ASSERT_EQ(p.status, 0) << p.err;
  const EmulatorOptions defaults;
  EXPECT_EQ(p.args.pty_link, "/tmp/lms");
  EXPECT_EQ(p.args.options.variant, defaults.variant);
  EXPECT_EQ(p.args.options.units, defaults.units);
  EXPECT_EQ(p.args.options.initial_baud, defaults.initial_baud);
  EXPECT_EQ(p.args.options.status, defaults.status);
  EXPECT_FALSE(p.args.options.faults.device_fault);
  EXPECT_EQ(p.args.options.faults.corrupt_crc_every, 0u);
}

TEST(Lms200EmulatorOptions, EveryOptionReachesTheEmulatorOptions) {
  const Parsed p = parse_emulator({"--pty", "/tmp/lms", "--variant", "100/0.25", "--units", "mm", "--baud", "38400",
                                   "--mode", "0x06", "--indices", "on", "--status", "0x12", "--fault", "crc=7",
                                   "--fault", "truncate=11", "--fault", "false-header=13", "--fault", "oversize-len=17",
                                   "--fault", "invalid-values=19", "--fault", "dazzle=23", "--fault", "no-ack",
                                   "--fault", "device-fault", "--fault", "silent", "--pose", "1.5,2,0.25"});
  ASSERT_EQ(p.status, 0) << p.err;
  const EmulatorOptions& o = p.args.options;
  EXPECT_EQ(o.variant, (Variant{100, 25}));
  EXPECT_EQ(o.units, Units::mm);
  EXPECT_EQ(o.initial_baud, 38400u);
  EXPECT_EQ(o.measuring_mode, MeasuringMode::range32_field_a);
  EXPECT_EQ(o.availability, kAvailabilityRealTimeIndices);
  EXPECT_EQ(o.status, 0x12);
  EXPECT_EQ(o.faults.corrupt_crc_every, 7u);
  EXPECT_EQ(o.faults.truncate_every, 11u);
  EXPECT_EQ(o.faults.false_header_every, 13u);
  EXPECT_EQ(o.faults.oversize_len_every, 17u);
  EXPECT_EQ(o.faults.invalid_values_every, 19u);
  EXPECT_EQ(o.faults.dazzle_every, 23u);
  EXPECT_TRUE(o.faults.suppress_ack);
  EXPECT_TRUE(o.faults.device_fault);
  EXPECT_TRUE(o.faults.silent);
  EXPECT_TRUE(p.args.have_pose);
  EXPECT_DOUBLE_EQ(p.args.pose[0], 1.5);
  EXPECT_DOUBLE_EQ(p.args.pose[2], 0.25);
  // 180/1 and cm, the other spellings.
  const Parsed q = parse_emulator({"--pty", "x", "--variant", "180/1", "--units", "cm", "--indices", "off"});
  ASSERT_EQ(q.status, 0) << q.err;
  EXPECT_EQ(q.args.options.variant, (Variant{180, 100}));
  EXPECT_EQ(q.args.options.units, Units::cm);
  EXPECT_EQ(q.args.options.availability, 0);
}

TEST(Lms200EmulatorOptions, BadValuesAreRefusedWithWhatWasExpected) {
  struct Case {
    std::vector<std::string> args;
    const char* message;
  };
  const Case cases[] = {
      {{"--variant", "180/0.25"}, "--variant: expected a variant: 180/1, 180/0.5, 100/1, 100/0.5 or 100/0.25"},
      {{"--variant", "180"}, "got '180'"},
      {{"--variant", "100/0"}, "--variant: expected"},
      {{"--units", "dm"}, "--units: expected cm or mm, got 'dm'"},
      {{"--baud", "115200"}, "--baud: expected a power-on rate: 9600, 19200, 38400 or 500000"},
      {{"--mode", "0x07"}, "--mode: expected a measuring mode"},
      {{"--indices", "yes"}, "--indices: expected on or off"},
      {{"--status", "0x100"}, "--status: expected a status byte"},
      {{"--fault", "crc"}, "--fault crc needs a period, e.g. crc=10"},
      {{"--fault", "crc=0"}, "--fault crc needs a period"},
      {{"--fault", "dazzle=x"}, "--fault dazzle needs a period"},
      {{"--fault", "no-ack=1"}, "--fault no-ack takes no value"},
      {{"--fault", "melted"}, "unknown fault 'melted' (crc=N, truncate=N"},
      {{"--colour", "red"}, "unknown option '--colour'"},
      {{"--units"}, "--units needs a value"},
      {{"--pose", "1,2"}, "--pose: expected X,Y,TH"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {"--pty", "/tmp/lms"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Parsed p = parse_emulator(args);
    EXPECT_EQ(p.status, 2) << c.args[0];
    EXPECT_NE(p.err.find(c.message), std::string::npos) << p.err;
  }
  const Parsed no_pty = parse_emulator({"--units", "mm"});
  EXPECT_EQ(no_pty.status, 2);
  EXPECT_NE(no_pty.err.find("--pty LINK is required"), std::string::npos) << no_pty.err;
}

std::string contents(std::FILE* f) {
  std::fflush(f);
  std::string text;
  std::rewind(f);
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  return text;
}

TEST(Lms200EmulatorCommand, AFaultFromTheCommandLineIsSeenThroughTheDriver) {
  const std::string link = "/tmp/sen3bot-lms200-fault-" + std::to_string(getpid());
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::vector<std::string> args = {"sen3bot-sim", "lms200-emulator", "--pty", link, "--baud", "38400", "--variant",
                                     "100/1", "--units", "mm", "--fault", "device-fault"};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::FILE* devnull = std::fopen("/dev/null", "w");
    _exit(sim::sim_cli_main(static_cast<int>(args.size()), argv.data(), out, devnull));
  }
  // Wait for the banner (under qemu-user start-up takes a while).
  for (int waited_ms = 0; waited_ms < 30'000 && contents(out).find("until SIGINT") == std::string::npos;
       waited_ms += 50)
    usleep(50'000);
  const std::string banner = contents(out);
  EXPECT_NE(banner.find("at 38400 baud, 100/100, mm, status 0x10 (device fault)"), std::string::npos) << banner;
  // The scanner is already at 38400, in 100/1 and mm: the driver only reads and streams.
  const CliRun r = run_cli({"scan", "--port", link, "--baud", "38400", "--variant", "100/1", "--units", "mm", "--count",
                            "2", "--timeout", "40"});
  ASSERT_EQ(kill(child, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const std::string text = contents(out);
  std::fclose(out);
  EXPECT_NE(text.find("requests "), std::string::npos) << text;
  ASSERT_EQ(r.status, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    EXPECT_NE(line.find("\"status\":\"0x13\",\"device_status\":1,\"fault\":true"), std::string::npos)
        << line.substr(0, 200);
    EXPECT_NE(line.find("\"count\":101"), std::string::npos);
  }
  EXPECT_EQ(n, 2);
}

}  // namespace
}  // namespace sen3bot::lms200
