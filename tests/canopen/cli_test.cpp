// `sen3bot can dump` on the e-stop scenario's log (golden lines, the line count, --node,
// --count, standard input), bad lines and error frames, and `can io` against the emulated node
// (`sen3bot-sim can io --iface sim`, the robot's command over the simulator's node); bad
// command lines are refused with exit status 2. The commands run through the whole command
// line (cli_main, sim_cli_main), as the binaries run them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "command_capture.hpp"
#include "sim_commands.hpp"

namespace sen3bot::firmware {
namespace {

const std::string kLog = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/can/io_node_estop.log";

int sen3bot_main(int argc, char** argv, std::FILE* out, std::FILE* err) { return cli_main(argc, argv, out, err); }

testing::CommandOutcome sen3bot(std::vector<std::string> args) {
  args.insert(args.begin(), "sen3bot");
  return testing::run_command(sen3bot_main, std::move(args));
}

int sim_main(int argc, char** argv, std::FILE* out, std::FILE* err) { return sim::sim_cli_main(argc, argv, out, err); }

testing::CommandOutcome sen3bot_sim(std::vector<std::string> args) {
  args.insert(args.begin(), "sen3bot-sim");
  return testing::run_command(sim_main, std::move(args));
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::size_t count_lines_in(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += line.empty() ? 0 : 1;
  return n;
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A temporary file with the given text, removed at the end of the test.
struct TempFile {
  explicit TempFile(const std::string& text) {
    char name[] = "/tmp/sen3bot-can-XXXXXX";
    const int fd = ::mkstemp(name);
    path = name;
    if (fd >= 0) {
      (void)!::write(fd, text.data(), text.size());
      ::close(fd);
    }
  }
  ~TempFile() { std::remove(path.c_str()); }
  std::string path;
};

TEST(CanDump, DecodesTheEstopLogOneObjectPerFrame) {
  const testing::CommandOutcome o = sen3bot({"can", "dump", kLog});
  ASSERT_EQ(o.code, 0) << o.err;
  const std::vector<std::string> lines = lines_of(o.out);
  EXPECT_EQ(lines.size(), count_lines_in(kLog));
  ASSERT_GE(lines.size(), 150u);
  // The master's first NMT (the node not powered yet), the node's boot-up, the first SDO write.
  EXPECT_EQ(lines[0],
            R"({"t_s":1717405200.000176,"interface":"can0","id":"000","kind":"nmt","data":"8210",)"
            R"("command":"reset_communication","target":16})");
  EXPECT_EQ(lines[1], R"({"t_s":1717405200.300860,"interface":"can0","id":"710","kind":"heartbeat","node":16,)"
                      R"("data":"00","state":"boot_up"})");
  EXPECT_EQ(lines[2], R"({"t_s":1717405200.310272,"interface":"can0","id":"610","kind":"sdo_request","node":16,)"
                      R"("data":"2B17100064000000","sdo":"download_request","index":"0x1017","sub":0,"size":2,)"
                      R"("value":100})");
  // The e-stop press (input 1 low), the EMCY, the outputs going red.
  const auto find = [&](const std::string& key) {
    for (const std::string& l : lines)
      if (has(l, key)) return l;
    return std::string();
  };
  EXPECT_EQ(find("1717405203.000860"), R"({"t_s":1717405203.000860,"interface":"can0","id":"190","kind":"tpdo",)"
                                       R"("node":16,"pdo":1,"data":"00","inputs":"0x00","inputs_on":[]})");
  EXPECT_EQ(find(R"("kind":"emcy")"),
            R"({"t_s":1717405204.500972,"interface":"can0","id":"090","kind":"emcy","node":16,)"
            R"("data":"1023030000000000","code":"0x2310","register":"0x03","description":"current",)"
            R"("vendor":"0000000000"})");
  EXPECT_EQ(find("1717405203.010160"), R"({"t_s":1717405203.010160,"interface":"can0","id":"210","kind":"rpdo",)"
                                       R"("node":16,"pdo":1,"data":"04","outputs":"0x04","outputs_on":[3]})");
  // The last line: the master asking the lost node for a boot-up.
  EXPECT_TRUE(has(lines.back(), R"("command":"reset_communication","target":16)")) << lines.back();
}

TEST(CanDump, CountStopsAfterNFrames) {
  const testing::CommandOutcome o = sen3bot({"can", "dump", kLog, "--count", "3"});
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(lines_of(o.out).size(), 3u);
}

TEST(CanDump, ReadsStandardInput) {
  std::FILE* log = std::fopen(kLog.c_str(), "r");
  ASSERT_NE(log, nullptr);
  const int saved = ::dup(0);
  ASSERT_GE(saved, 0);
  ::dup2(::fileno(log), 0);
  const testing::CommandOutcome o = sen3bot({"can", "dump", "-"});
  ::dup2(saved, 0);
  ::close(saved);
  std::fclose(log);
  std::clearerr(stdin);
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(lines_of(o.out).size(), count_lines_in(kLog));
}

// Good and bad lines, error frames, and frames of two nodes.
const char* const kMixed =
    "(1717405200.000100) can0 000#0100\n"                          // 1 NMT start, all nodes
    "this is not a candump line\n"                                   // 2 bad
    "(1717405200.000200) can0 711#05\n"                              // 3 node 17 heartbeat
    "\n"                                                             // 4 blank: skipped
    "(1717405200.000300) can0 123##1112233\n"                        // 5 CAN FD: refused
    "(1717405200.000400) can0 20000040#0000000000000000\n"           // 6 bus-off
    "(1717405200.000500) can0 20000004#0030000000000000\n"           // 7 controller: rx/tx passive
    "(1717405200.000600) can0 20000100#0000000000000000\n"           // 8 restarted
    "(1717405200.000700) can0 590#8000620100000206\n"                // 9 SDO abort from node 16
    "(1717405200.000800) can0 710#\n"                                // 10 heartbeat without data
    "(1717405200.000900) can0 0101#00\n"                             // 11 bad id length
    "(1717405200.001000) can0 12345678#DEADBEEF\n";                  // 12 extended id

TEST(CanDump, BadLinesAreObjectsWithTheirNumberAndTheDumpGoesOn) {
  const TempFile file(kMixed);
  const testing::CommandOutcome o = sen3bot({"can", "dump", file.path});
  EXPECT_EQ(o.code, 1);
  EXPECT_TRUE(has(o.err, "3 bad lines of 12")) << o.err;
  const std::vector<std::string> lines = lines_of(o.out);
  ASSERT_EQ(lines.size(), 11u) << o.out;
  EXPECT_EQ(lines[1], R"({"line":2,"error":"candump line, column 1: expected '(' and the time"})");
  EXPECT_TRUE(has(lines[3], R"({"line":5,"error":"candump line, column 30: a CAN FD frame)")) << lines[3];
  EXPECT_EQ(lines[4], R"({"t_s":1717405200.000400,"interface":"can0","id":"20000040","kind":"error",)"
                      R"("events":["bus_off"],"link":"bus-off","data":"0000000000000000"})");
  EXPECT_EQ(lines[5], R"({"t_s":1717405200.000500,"interface":"can0","id":"20000004","kind":"error",)"
                      R"("events":["controller"],"controller":["rx_passive","tx_passive"],"link":"error-passive",)"
                      R"("data":"0030000000000000"})");
  EXPECT_TRUE(has(lines[6], R"("events":["restarted"],"link":"error-active")")) << lines[6];
  EXPECT_TRUE(has(lines[7], R"("sdo":"abort","index":"0x6200","sub":1,"abort_code":"0x06020000",)"
                            R"("abort":"object does not exist in the object dictionary")"))
      << lines[7];
  EXPECT_TRUE(has(lines[8], R"("kind":"heartbeat","node":16,"data":"","malformed":"CANopen heartbeat 0x710: 0 data )"
                            R"(bytes, needs 1")"))
      << lines[8];
  EXPECT_TRUE(has(lines[9], R"({"line":11,"error":"candump line, column 26: the id needs 3 hex digits)")) << lines[9];
  EXPECT_TRUE(has(lines[10], R"("id":"12345678","kind":"other","extended":true,"data":"DEADBEEF")")) << lines[10];
}

TEST(CanDump, NodeKeepsThatNodesFramesBroadcastsAndTheLink) {
  const TempFile file(kMixed);
  const testing::CommandOutcome o = sen3bot({"can", "dump", file.path, "--node", "17"});
  EXPECT_EQ(o.code, 1);  // the bad lines are still bad
  std::vector<std::string> frames;
  for (const std::string& l : lines_of(o.out))
    if (!has(l, R"("line":)")) frames.push_back(l);
  ASSERT_EQ(frames.size(), 5u) << o.out;
  EXPECT_TRUE(has(frames[0], R"("command":"start","target":0)"));
  EXPECT_TRUE(has(frames[1], R"("id":"711")"));
  EXPECT_TRUE(has(frames[2], R"("kind":"error")"));
  EXPECT_TRUE(has(frames[4], R"("events":["restarted"])"));
  // The log is all node 16 and NMT to it: nothing of node 17, and a clean exit.
  const testing::CommandOutcome none = sen3bot({"can", "dump", kLog, "--node", "17"});
  EXPECT_EQ(none.code, 0);
  EXPECT_EQ(none.out, "");
}

TEST(CanDump, CommandLineAndSourceErrors) {
  EXPECT_EQ(sen3bot({"can", "dump"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, "--node", "0"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, "--node", "128"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, "--node", "x"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, "--node"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, "--count", "0"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, kLog}).code, 2);
  EXPECT_EQ(sen3bot({"can", "dump", kLog, "--bogus"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "bogus"}).code, 2);
  const testing::CommandOutcome missing = sen3bot({"can", "dump", "/nonexistent/bus.log"});
  EXPECT_EQ(missing.code, 1);
  EXPECT_TRUE(has(missing.err, "sen3bot can dump: /nonexistent/bus.log: No such file or directory")) << missing.err;
  const testing::CommandOutcome directory = sen3bot({"can", "dump", "/tmp"});
  EXPECT_EQ(directory.code, 1);
  EXPECT_TRUE(has(directory.err, "is a directory")) << directory.err;
  // No such file and no such CAN interface (or no CAN in the kernel at all): both said.
  const testing::CommandOutcome iface = sen3bot({"can", "dump", "nosuchcan9"});
  EXPECT_EQ(iface.code, 1);
  EXPECT_TRUE(has(iface.err, "nosuchcan9: no such file, and as a CAN interface: ")) << iface.err;
}

TEST(CanIo, SimBringsTheNodeUpSetsAnOutputAndReadsTheInputs) {
  const testing::CommandOutcome o =
      sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--set", "2=1", "--sim-inputs", "0x05"});
  ASSERT_EQ(o.code, 0) << o.err;
  ASSERT_EQ(lines_of(o.out).size(), 1u) << o.out;
  EXPECT_TRUE(has(o.out, R"({"iface":"sim","node":16,"state":"operational","heartbeat":"operational",)"
                         R"("inputs_valid":true,"inputs":"0x05","inputs_on":[1,3],"outputs":"0x02","outputs_on":[2],)"
                         R"("link":"error-active")"))
      << o.out;
  EXPECT_TRUE(has(o.out, R"("events":{"boot_up":1,"heartbeat_lost":0,"configured":1,"sdo_abort":0,)"
                         R"("sdo_timeout":0,"emergency":0,"emergency_reset":0,"unexpected_frame":0})"))
      << o.out;
  // The emulated node has them: the outputs arrived, not only went out.
  EXPECT_TRUE(has(o.out, R"("emulator":{"state":"operational","outputs":"0x02","outputs_on":[2]}})")) << o.out;
}

TEST(CanIo, LaterSetsOfTheSameOutputWin) {
  const testing::CommandOutcome o =
      sen3bot_sim({"can", "io", "--iface", "sim", "--node", "5", "--set", "1=1", "--set", "8=1", "--set", "1=0"});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_TRUE(has(o.out, R"("node":5,)")) << o.out;
  EXPECT_TRUE(has(o.out, R"("outputs":"0x80","outputs_on":[8])")) << o.out;
  EXPECT_TRUE(has(o.out, R"("inputs":"0x00","inputs_on":[])")) << o.out;
}

TEST(CanIo, ANodeThatNeverAnswersTimesOutWithTheMastersState) {
  const testing::CommandOutcome o =
      sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--sim-silent", "--timeout", "0.3"});
  EXPECT_EQ(o.code, 1);
  EXPECT_EQ(o.out, "");
  EXPECT_TRUE(has(o.err, "sen3bot-sim can io: node 16 on sim not operational after 0.3 s: master state waiting_boot, "
                         "no heartbeat heard, link error-active"))
      << o.err;
  EXPECT_TRUE(has(o.err, "boot_up 0 heartbeat_lost 0 configured 0")) << o.err;
}

TEST(CanIo, CommandLineErrors) {
  EXPECT_EQ(sen3bot_sim({"can", "io"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--node", "16"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--set", "0=1"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--set", "9=1"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--set", "2=2"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--set", "2"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--timeout", "-1"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--sim-inputs", "0x100"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--bogus", "1"}).code, 2);
  EXPECT_EQ(sen3bot_sim({"can", "io", "--iface", "sim", "--node", "16", "--timeout"}).code, 2);
  const testing::CommandOutcome sim_only =
      sen3bot_sim({"can", "io", "--iface", "can0", "--node", "16", "--sim-inputs", "1"});
  EXPECT_EQ(sim_only.code, 2);
  EXPECT_TRUE(has(sim_only.err, "only with --iface sim")) << sim_only.err;
  // The robot's binary has no emulated node, and says where it is.
  EXPECT_EQ(sen3bot({"can", "io"}).code, 2);
  EXPECT_EQ(sen3bot({"can", "io", "--node", "16"}).code, 2);
  const testing::CommandOutcome robot_sim = sen3bot({"can", "io", "--iface", "sim", "--node", "16"});
  EXPECT_EQ(robot_sim.code, 2);
  EXPECT_TRUE(has(robot_sim.err, "sen3bot-sim can io --iface sim")) << robot_sim.err;
  EXPECT_EQ(sen3bot({"can", "io", "--iface", "can0", "--node", "16", "--sim-inputs", "1"}).code, 2);
  // A SocketCAN interface that cannot be opened (no such interface, or no CAN in the kernel).
  const testing::CommandOutcome real =
      sen3bot({"can", "io", "--iface", "nosuchcan9", "--node", "16", "--timeout", "0.2"});
  EXPECT_EQ(real.code, 1);
  EXPECT_TRUE(has(real.err, "sen3bot can io: ")) << real.err;
}

}  // namespace
}  // namespace sen3bot::firmware
