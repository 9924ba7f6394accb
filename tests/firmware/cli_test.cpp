#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "cli.hpp"
#include "sim_commands.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

// What a child wrote so far, read without moving the file offset the child shares with us.
std::string peek_all(std::FILE* f) {
  std::string text;
  std::array<char, 4096> buf;
  off_t offset = 0;
  for (;;) {
    const ssize_t n = pread(fileno(f), buf.data(), buf.size(), offset);
    if (n <= 0) return text;
    text.append(buf.data(), static_cast<std::size_t>(n));
    offset += n;
  }
}

std::string read_all(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string text;
  std::array<char, 4096> buf;
  while (std::size_t n = std::fread(buf.data(), 1, buf.size(), f)) text.append(buf.data(), n);
  return text;
}

struct Outcome {
  int code;
  std::string out;
  std::string err;
};

using Main = int (*)(int, char**, std::FILE*, std::FILE*);

Outcome run_main(Main main, const char* program, std::vector<std::string> args) {
  args.insert(args.begin(), program);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  const int code = main(static_cast<int>(args.size()), argv.data(), out, err);
  Outcome o{code, read_all(out), read_all(err)};
  std::fclose(out);
  std::fclose(err);
  return o;
}

// The robot's binary and the simulator's.
Outcome run(std::vector<std::string> args) { return run_main(cli_main, "sen3bot", std::move(args)); }
Outcome run_sim(std::vector<std::string> args) { return run_main(sim::sim_cli_main, "sen3bot-sim", std::move(args)); }

const std::string kSim = SEN3BOT_SOURCE_DIR "/config/sim.yaml";
const std::string kRobot = SEN3BOT_SOURCE_DIR "/config/robot.yaml";

TEST(Cli, HelpAndVersion) {
  Outcome o = run({"--help"});
  EXPECT_EQ(o.code, 0);
  EXPECT_NE(o.out.find("run --config FILE"), std::string::npos);
  o = run({"version"});
  EXPECT_EQ(o.code, 0);
  EXPECT_EQ(o.out.rfind("sen3bot ", 0), 0u);
  o = run({});
  EXPECT_EQ(o.code, 2);
  o = run({"fly"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("unknown command 'fly'"), std::string::npos);
  // The simulator's commands are not the robot's.
  for (const char* command : {"sim", "p2os-emulator", "lms200-emulator"}) {
    o = run({command, "--list"});
    EXPECT_EQ(o.code, 2) << command;
    EXPECT_NE(o.err.find("unknown command"), std::string::npos) << command;
  }
  o = run_sim({"--help"});
  EXPECT_EQ(o.code, 0);
  for (const char* command : {"run --config", "sim --scenario", "p2os-emulator", "lms200-emulator"})
    EXPECT_NE(o.out.find(command), std::string::npos) << command;
  o = run_sim({"version"});
  EXPECT_EQ(o.out.rfind("sen3bot-sim ", 0), 0u);
}

TEST(Cli, TheRobotRefusesASimulatedRobotAndLockstepTime) {
  Outcome o = run({"run", "--config", kSim});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("sim: a simulated robot: run this configuration with sen3bot-sim"), std::string::npos) << o.err;
  o = run({"run", "--config", kRobot, "--clock", "lockstep"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("lockstep time needs a simulated robot"), std::string::npos) << o.err;
}

TEST(Cli, RunRejectsBadArguments) {
  EXPECT_EQ(run({"run"}).code, 2);
  EXPECT_EQ(run({"run", "--config"}).code, 2);
  Outcome o = run_sim({"run", "--config", kSim, "--duration", "soon"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--duration: expected seconds"), std::string::npos);
  o = run({"run", "--config", "/no/such.yaml"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("/no/such.yaml: cannot open"), std::string::npos);
}

// The data flow of a configuration, without starting anything; bad arguments and files are
// errors naming them.
TEST(Cli, GraphPrintsTheWiringAndRefusesBadInput) {
  Outcome o = run({"graph", "--config", kSim});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("thread io\n  laser "), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("  scan                 laser -> safety, localization, controller, planner"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("  camera       needs devices.camera"), std::string::npos) << o.out;
  o = run({"graph", "--config", kSim, "--mermaid"});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out.rfind("flowchart LR\n", 0), 0u) << o.out;
  EXPECT_NE(o.out.find("  safety --> t_command\n"), std::string::npos) << o.out;
  EXPECT_EQ(run({"graph"}).code, 2);
  EXPECT_EQ(run({"graph", "--config", kSim, "--dot"}).code, 2);
  o = run({"graph", "--config", "/no/such.yaml"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("/no/such.yaml: cannot open"), std::string::npos) << o.err;
}

TEST(Cli, LockstepRunPrintsStatusAndStatistics) {
  // A duration shorter than the mission: the run ends on time, the mission is reported as
  // still driving, and that is not a failure.
  Outcome o = run_sim({"run", "--config", kSim, "--duration", "12"});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("lockstep simulated clock"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("memory budgets"), std::string::npos);
  // Every row but the camera's, the detectors' and the people's (config/sim.yaml has none),
  // the fleet's (its mission gives the goals), the collaborative mode's three (no cobot) and the
  // view's (off).
  EXPECT_NE(o.out.find("status  " + std::to_string(kTaskTable.size() - 10) + " tasks"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("simulated 12.000 s"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("task statistics"), std::string::npos);
  // health at 10 Hz for 12 s.
  EXPECT_NE(o.out.find("health         control        100000      500  60       120"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("on the sim board"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("ground truth: "), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("mission driving: 0 of 2 goals reached"), std::string::npos) << o.out;
}

TEST(Cli, TheMainJobCompletesTheSimulatedMission) {
  // README's main job: both goals reached through the real drivers and emulators, nothing
  // hit while the robot was moving, and the run ends when the mission does.
  Outcome o = run_sim({"run", "--config", kSim});
  ASSERT_EQ(o.code, 0) << o.out << o.err;
  EXPECT_NE(o.out.find("mission complete: 2 of 2 goals reached"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("(0 of the robot's doing)"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("simulated 120.000 s"), std::string::npos) << o.out;
}

TEST(Cli, RealTimeRunStopsCleanlyOnSigint) {
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::string a0 = "sen3bot-sim", a1 = "run", a2 = "--config", a3 = kSim, a4 = "--clock", a5 = "realtime", a6 = "--duration", a7 = "0";
    char* argv[] = {a0.data(), a1.data(), a2.data(), a3.data(), a4.data(), a5.data(), a6.data(), a7.data(), nullptr};
    std::FILE* devnull = std::fopen("/dev/null", "w");
    _exit(sim::sim_cli_main(8, argv, out, devnull));
  }
  // Stop it once it is running (under an emulator such as qemu-user start-up takes a while).
  for (int waited_ms = 0; waited_ms < 30'000 && peek_all(out).find("memory budgets") == std::string::npos; waited_ms += 50)
    usleep(50'000);
  usleep(200'000);
  ASSERT_EQ(kill(child, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const std::string text = read_all(out);
  std::fclose(out);
  EXPECT_NE(text.find("stopped by SIGINT"), std::string::npos) << text;
  EXPECT_NE(text.find("task statistics"), std::string::npos) << text;
}

TEST(Cli, CaptureDumpReportsAMissingFile) {
  Outcome o = run({"capture", "dump", "/no/such.s3bcap"});
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("/no/such.s3bcap"), std::string::npos) << o.err;
  EXPECT_EQ(run({"capture"}).code, 2);
}

}  // namespace
}  // namespace sen3bot::firmware
