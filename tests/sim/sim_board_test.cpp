// The simulated board: links whose port is "sim" reach the emulators, other ports the host; the
// world steps on its 5 ms grid as the lockstep clock advances, or on the board's own thread in
// real time; the discrete lines a scenario drives.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "sen3bot/p2os/driver.hpp"
#include "sim_rig.hpp"

namespace sen3bot::sim {
namespace {

TEST(SimBoard, TheWorldStepsOnItsGridAsTheLockstepClockAdvances) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  SimBoard& board = *rig.board;
  hal::SimClock* clock = board.lockstep_clock();
  ASSERT_NE(clock, nullptr);
  EXPECT_EQ(&board.clock(), clock);
  clock->advance_to(hal::millis(12));
  EXPECT_EQ(board.simulation().truth().stamp_ns, hal::millis(10));  // steps at 0, 5 and 10 ms
  clock->advance_to(hal::millis(15));
  EXPECT_EQ(board.simulation().truth().stamp_ns, hal::millis(15));
  EXPECT_NEAR(board.simulation().truth().pose.x_m, rig.world.start_pose.x_m, 1e-9);
}

TEST(SimBoard, ASimPortReachesTheEmulatorAndOtherLinksAreRefused) {
  testing::SimRig rig = testing::load_sim_rig();
  SimBoard& board = *rig.board;
  Result<hal::Link> base = board.open_link("base", hal::LinkRequest{"sim", 9600});
  ASSERT_TRUE(base) << base.error().c_str();
  p2os::P2osDriver driver(p2os::P2osConfig{});
  hal::SimClock* clock = board.lockstep_clock();
  ASSERT_NE(clock, nullptr);
  driver.attach(*base->stream, clock->now());
  for (int i = 0; i < 2000 && driver.state().link != p2os::LinkState::connected; ++i) {
    driver.step(clock->now());
    clock->advance_by(hal::millis(1));
  }
  EXPECT_EQ(driver.state().link, p2os::LinkState::connected);

  Result<hal::Link> laser = board.open_link("laser", hal::LinkRequest{"sim", 38400});
  ASSERT_TRUE(laser) << laser.error().c_str();
  EXPECT_NE(laser->baud_control, nullptr);  // the simulated line follows the driver's rate

  Result<hal::Link> camera = board.open_link("camera", hal::LinkRequest{"sim", 0});
  ASSERT_FALSE(camera);
  EXPECT_EQ(camera.error().code(), Errc::not_found);
  EXPECT_NE(std::string(camera.error().message()).find("no simulated device behind the 'camera' link"),
            std::string::npos);

  // Not "sim": the host's device, as on the robot.
  Result<hal::Link> host = board.open_link("laser", hal::LinkRequest{"/dev/no-such-tty", 38400});
  ASSERT_FALSE(host);
  EXPECT_NE(std::string(host.error().message()).find("/dev/no-such-tty"), std::string::npos);
}

TEST(SimBoard, InRealTimeTheWorldStepsOnTheBoardsOwnThread) {
  testing::SimRig rig = testing::load_sim_rig();
  rig.make_board(false);
  SimBoard& board = *rig.board;
  EXPECT_EQ(board.lockstep_clock(), nullptr);
  Result<hal::Link> base = board.open_link("base", hal::LinkRequest{"sim", 9600});
  ASSERT_TRUE(base) << base.error().c_str();
  EXPECT_NE(base->baud_control, nullptr);  // a real pty, opened as a serial port
  const auto before = std::chrono::steady_clock::now();
  ASSERT_TRUE(board.start());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  board.stop();
  const auto elapsed_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - before).count();
  // Steps of 5 ms on the board's thread: several of them, and never ahead of the wall clock
  // (how many fit depends on how busy the machine is).
  EXPECT_GE(board.simulation().truth().stamp_ns, hal::millis(20));
  EXPECT_LE(board.simulation().truth().stamp_ns, elapsed_ns + hal::millis(5));
}

TEST(SimBoard, TheDiscreteLinesAreTheScenariosToDrive) {
  testing::SimRig rig = testing::load_sim_rig();
  SimBoard& board = *rig.board;
  ASSERT_NE(board.input("estop"), nullptr);
  ASSERT_NE(board.output("light"), nullptr);
  EXPECT_EQ(board.input("bumper"), nullptr);
  EXPECT_FALSE(*board.input("estop")->read());
  ASSERT_TRUE(board.estop().write(true));
  EXPECT_TRUE(*board.input("estop")->read());
  ASSERT_TRUE(board.output("light")->write(true));
  EXPECT_TRUE(board.light().state());
}

}  // namespace
}  // namespace sen3bot::sim

namespace sen3bot::sim {
namespace {

std::string sim_error(const std::string& section) {
  Result<SimulationConfig> r = parse_sim_config("robot: { name: x }\n" + section, "sim.yaml", {});
  return r ? std::string() : std::string(r.error().message());
}

TEST(SimConfig, TheShippedSectionAndItsErrors) {
  const testing::SimRig rig = testing::load_sim_rig();
  EXPECT_EQ(rig.world.map_path, SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");  // relative to the file
  ASSERT_EQ(rig.world.movers.size(), 1u);
  EXPECT_TRUE(rig.world.movers[0].person);
  EXPECT_DOUBLE_EQ(rig.world.movers[0].speed_m_s, 0.6);
  EXPECT_DOUBLE_EQ(rig.world.laser_mount.x_m, rig.config.laser_mount.x_m);  // the scanner sits where the firmware thinks

  EXPECT_NE(sim_error("").find("sim.yaml: sim: missing"), std::string::npos) << sim_error("");
  EXPECT_NE(sim_error("sim: { seed: 1 }\n").find("sim.map: missing"), std::string::npos);
  EXPECT_NE(sim_error("sim: { map: m.yaml, weather: rain }\n").find("sim.weather: unknown key"), std::string::npos);
  EXPECT_NE(sim_error("sim: { map: m.yaml, boxes: [ { path: [[1, 1]], shape: cone } ] }\n")
                .find("sim.boxes[0].shape: expected circle or square, got 'cone'"),
            std::string::npos);
  EXPECT_NE(sim_error("sim: { map: m.yaml, people: [ { path: [] } ] }\n").find("sim.people[0].path: needs at least one point"),
            std::string::npos);
  EXPECT_NE(sim_error("sim: { map: m.yaml, laser_max_range_m: 200 }\n").find("sim.laser_max_range_m: value 200 is outside"),
            std::string::npos);
  Result<SimulationConfig> ranged =
      parse_sim_config("robot: { name: x }\nsim: { map: m.yaml, laser_max_range_m: 30 }\n", "sim.yaml", {});
  ASSERT_TRUE(ranged) << ranged.error().c_str();
  EXPECT_DOUBLE_EQ(ranged->laser_max_range_m, 30.0);
  EXPECT_DOUBLE_EQ(rig.world.laser_max_range_m, 8.0);  // the LMS200's mm mode, the default
}

}  // namespace
}  // namespace sen3bot::sim
