// Sense-to-act latency of the whole firmware, measured on the wire in lockstep: the P2OS VEL
// packets the base driver writes, against the controller command and the laser scan behind
// them. The budget is firmware::kSenseToActBudgetNs (task_table.hpp); docs/firmware.md explains
// it. The worst-phase test puts a box in the robot's way just after a scan was taken, at the
// distance the safety filter promises to stop in, and the robot must stop short of it.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/protocol.hpp"
#include "sim_rig.hpp"
#include "vel_recorder.hpp"
#include "task_table.hpp"
#include "stats.hpp"

namespace sen3bot {
namespace {

using testing::VelPacket;
using testing::VelRecorder;

// The acquisition time of the scan a safety decision used: its stamp (when the LMS200 began
// sending it, the sweep just done), which the decision's age counts from.
hal::Nanos scan_acquired_ns(const VelPacket& p) {
  return p.command.stamp_ns - static_cast<hal::Nanos>(std::llround(p.safety.value.scan_age_s * 1e9));
}

TEST(SenseToAct, EveryControllerCommandReachesTheWireWithinTheBudget) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  std::FILE* sink = std::fopen("/dev/null", "w");
  firmware::Firmware fw(rig.config, *rig.board, sink);
  VelRecorder recorder(fw);
  rig.board->set_wire_tap(&recorder);
  ASSERT_TRUE(fw.init());
  // Every request the controller publishes, seen each simulated millisecond.
  std::vector<tasks::Sample<msg::VelocityCommand>> requests;
  for (hal::Nanos t = 0; t < hal::seconds(40); t += hal::millis(1)) {
    ASSERT_TRUE(fw.scheduler().run_lockstep(rig.clock(), hal::millis(1)));
    tasks::Sample<msg::VelocityCommand> r;
    if (fw.request().read(r) && (requests.empty() || r.sequence != requests.back().sequence)) requests.push_back(r);
  }
  fw.shutdown();
  std::fclose(sink);

  // A request that changes the speed answers on the wire with the first VEL carrying its speed,
  // when the safety filter passed it unchanged.
  std::vector<double> command_ms;
  std::int32_t previous_mm_s = 0;
  for (const auto& r : requests) {
    const std::int32_t mm_s = static_cast<std::int32_t>(std::lround(r.value.v_m_s * 1000.0));
    if (mm_s == previous_mm_s) continue;
    previous_mm_s = mm_s;
    for (const VelPacket& p : recorder.packets) {
      if (p.t_ns < r.stamp_ns) continue;
      if (p.request.sequence == r.sequence && p.vel_mm_s == mm_s && p.command.value.v_m_s == r.value.v_m_s)
        command_ms.push_back(static_cast<double>(p.t_ns - r.stamp_ns) * 1e-6);
      break;
    }
  }
  std::vector<double> scan_age_ms;
  for (const VelPacket& p : recorder.packets)
    if (p.safety.sequence > 0) scan_age_ms.push_back(p.safety.value.scan_age_s * 1e3);
  ASSERT_GE(command_ms.size(), 20u) << "the mission should change its speed often";
  const double worst = *std::max_element(command_ms.begin(), command_ms.end());
  std::printf("controller command -> VEL on the wire: %zu speed changes, median %.1f ms, max %.1f ms (budget %.1f ms)\n",
              command_ms.size(), test::median(command_ms), worst, hal::to_seconds(firmware::kSenseToActBudgetNs) * 1e3);
  std::printf("age of the scan behind each VEL: median %.1f ms, max %.1f ms\n", test::median(scan_age_ms),
              *std::max_element(scan_age_ms.begin(), scan_age_ms.end()));
  EXPECT_LE(worst, hal::to_seconds(firmware::kSenseToActBudgetNs) * 1e3);
}

// A hall 14 m x 5 m with pillars along the walls, so localization has something to hold on to.
std::string write_hall_map(const std::string& dir) {
  constexpr int kWidth = 280, kHeight = 100;  // 0.05 m cells
  std::vector<std::uint8_t> pixels(kWidth * kHeight, 254);
  auto wall = [&](int x0, int y0, int x1, int y1) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) pixels[(kHeight - 1 - y) * kWidth + x] = 0;
  };
  wall(0, 0, kWidth - 1, 1);
  wall(0, kHeight - 2, kWidth - 1, kHeight - 1);
  wall(0, 0, 1, kHeight - 1);
  wall(kWidth - 2, 0, kWidth - 1, kHeight - 1);
  for (int x = 20; x < kWidth - 20; x += 37) {
    wall(x, 2, x + 5, 8);
    wall(x + 12, kHeight - 9, x + 17, kHeight - 3);
  }
  std::ofstream pgm(dir + "/hall.pgm", std::ios::binary);
  pgm << "P5\n" << kWidth << " " << kHeight << "\n255\n";
  pgm.write(reinterpret_cast<const char*>(pixels.data()), static_cast<std::streamsize>(pixels.size()));
  std::ofstream yaml(dir + "/hall.yaml");
  yaml << "image: hall.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
          "free_thresh: 0.196\n";
  return dir + "/hall.yaml";
}

struct HallRun {
  std::vector<VelPacket> packets;
  std::vector<hal::Nanos> scan_published_ns;  // when each new scan reached the bus
  std::vector<sim::GroundTruth> truth;        // per millisecond
  sim::RefereeReport report;
};

// Drives from (1.5, 2.5) m towards (13, 2.5) m, optionally with a box appearing; 1 ms slices.
HallRun drive_the_hall(const std::string& map, const world::MoverScript* box, double seconds) {
  testing::SimRig rig = testing::load_sim_rig();
  const msg::Pose2D start{1.5, 2.5, 0.0};
  rig.world.map_path = map;
  rig.world.start_pose = start;
  rig.world.movers.clear();
  if (box != nullptr) rig.world.movers.push_back(*box);
  rig.make_board();
  rig.config.navigation.map_path = map;
  rig.config.navigation.waypoints_path.clear();
  rig.config.navigation.mcl.initial_pose = start;
  rig.config.navigation.mission.goal_count = 1;
  rig.config.navigation.mission.goals[0] = {13.0, 2.5};
  rig.config.navigation.mission.start_delay_s = 1.0;
  HallRun run;
  std::FILE* sink = std::fopen("/dev/null", "w");
  firmware::Firmware fw(rig.config, *rig.board, sink);
  rig.board->referee().watch_estimate(&fw.pose_estimate());
  VelRecorder recorder(fw);
  rig.board->set_wire_tap(&recorder);
  EXPECT_TRUE(fw.init());
  std::uint64_t scan_seq = 0;
  for (hal::Nanos t = 0; t < hal::seconds(static_cast<std::int64_t>(seconds)); t += hal::millis(1)) {
    EXPECT_TRUE(fw.scheduler().run_lockstep(rig.clock(), hal::millis(1)));
    tasks::Sample<msg::ScanMessage> scan;
    if (fw.scan().read(scan) && scan.sequence != scan_seq) {
      scan_seq = scan.sequence;
      run.scan_published_ns.push_back(scan.stamp_ns);
    }
    run.truth.push_back(rig.board->simulation().truth());
  }
  fw.shutdown();
  std::fclose(sink);
  run.packets = std::move(recorder.packets);
  run.report = rig.board->referee().report();
  return run;
}

TEST(SenseToAct, ABoxAppearingAtTheWorstPhaseIsStoppedShortOfAtFullSpeed) {
  char dir_template[] = "/tmp/sen3bot-latency-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::string map = write_hall_map(dir_template);

  // First run: where the robot is at full speed, and when the scanner takes a sweep. The LMS200
  // streams back to back, so the next sweep is taken as one telegram's last byte arrives: a
  // box that appears a millisecond after that is first seen one whole scan interval later.
  const HallRun dry = drive_the_hall(map, nullptr, 12.0);
  const testing::SimRig reference = testing::load_sim_rig();
  const lms200::Lms200Config& laser = reference.config.devices.laser;
  const double interval_s = hal::to_seconds(lms200::scan_interval_ns(laser.variant, laser.baud));
  hal::Nanos appear_ns = -1;
  for (hal::Nanos t : dry.scan_published_ns) {
    const std::size_t ms = static_cast<std::size_t>(t / hal::millis(1));
    if (ms < dry.truth.size() && dry.truth[ms].speed_m_s > 0.49 && dry.truth[ms].pose.x_m > 3.0) {
      appear_ns = t + hal::millis(1);
      break;
    }
  }
  ASSERT_GE(appear_ns, 0) << "the robot never reached full speed";
  const sim::GroundTruth at = dry.truth[static_cast<std::size_t>(appear_ns / hal::millis(1))];
  const double v = at.speed_m_s;

  // The stop zone the safety filter sizes for the oldest scan it can act on: one interval on
  // the wire plus the sense-to-act budget.
  const double reaction_s = hal::to_seconds(firmware::kSenseToActBudgetNs);
  const double decel = reference.config.devices.base.trans_decel_mm_s2 / 1000.0;
  const double depth = reference.config.navigation.safety.stop_distance_m + v * (reaction_s + interval_s + reaction_s) +
                       v * v / (2.0 * decel);
  // Free travel from the robot's front to the box's near face when it appears: the robot covers
  // one more scan interval before a sweep sees it.
  const double front_m = nav::Footprint::pioneer().vertices[0].x_m;
  const double free_m = v * interval_s + depth + 0.02;
  world::MoverScript box;
  box.size_m = 0.4;
  box.shape = world::MoverShape::square;
  box.path = {{at.pose.x_m + std::abs(front_m) + free_m + box.size_m / 2, at.pose.y_m}};
  box.appear_time_s = hal::to_seconds(appear_ns);

  const HallRun run = drive_the_hall(map, &box, 12.0);
  EXPECT_EQ(run.report.contacts, 0u);
  // Until the robot has braked from full speed to a crawl: then the controller may creep and
  // plan around the box. It must have kept the safety filter's stop distance, give or take the
  // last centimetres of braking.
  double min_clearance = 1e9;
  bool braked = false;
  for (std::size_t ms = static_cast<std::size_t>(appear_ns / hal::millis(1)); ms < run.truth.size() && !braked; ++ms) {
    min_clearance = std::min(min_clearance, run.truth[ms].clearance_m);
    braked = std::abs(run.truth[ms].speed_m_s) < 0.05;
  }
  EXPECT_TRUE(braked);
  EXPECT_GT(min_clearance, 0.8 * reference.config.navigation.safety.stop_distance_m);
  if (std::getenv("SEN3BOT_LATENCY_TRACE") != nullptr)
    for (std::size_t ms = static_cast<std::size_t>(appear_ns / hal::millis(1)); ms < run.truth.size(); ms += 50)
      std::printf("t %.3f x %.3f v %.3f clearance %.3f\n", static_cast<double>(ms) / 1e3, run.truth[ms].pose.x_m,
                  run.truth[ms].speed_m_s, run.truth[ms].clearance_m);

  // The first VEL after the box appeared that slows the robot, and the scan it answers.
  const VelPacket* answer = nullptr;
  for (const VelPacket& p : run.packets)
    if (p.t_ns > appear_ns && p.vel_mm_s < std::lround(v * 1000.0) - 10) {
      answer = &p;
      break;
    }
  ASSERT_NE(answer, nullptr) << "the robot never slowed for the box";
  const hal::Nanos acquired = scan_acquired_ns(*answer);
  EXPECT_GE(acquired, appear_ns) << "answered a scan taken before the box was there";
  const double scan_to_vel_ms = static_cast<double>(answer->t_ns - acquired) * 1e-6;
  const double decoded_to_vel_ms = static_cast<double>(answer->t_ns - answer->scan.stamp_ns) * 1e-6;
  std::printf("box appeared at %.3f s, %.2f m ahead at %.2f m/s; first sweep with it %.1f ms later\n",
              hal::to_seconds(appear_ns), free_m, v, static_cast<double>(acquired - appear_ns) * 1e-6);
  std::printf("scan acquisition -> VEL %d mm/s on the wire: %.1f ms (telegram %.1f ms, decoded -> VEL %.1f ms); "
              "clearance when braked %.3f m\n",
              answer->vel_mm_s, scan_to_vel_ms, interval_s * 1e3, decoded_to_vel_ms, min_clearance);
  EXPECT_LE(decoded_to_vel_ms, hal::to_seconds(firmware::kSenseToActBudgetNs) * 1e3);
  EXPECT_LE(scan_to_vel_ms, (interval_s + hal::to_seconds(firmware::kSenseToActBudgetNs)) * 1e3 + 1.0);
}

}  // namespace
}  // namespace sen3bot
