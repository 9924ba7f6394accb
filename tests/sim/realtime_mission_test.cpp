// The main mission in real time while a CPU hog keeps every core busy, as a build beside the
// robot would: the firmware's threads on the monotonic clock, the drivers on real ptys, the
// simulated world on its own thread. Where the worker and the robot meet depends on how the
// machine schedules them. Asserted is what a late or slipped cycle must never cause: the robot
// driving into the map or a box, or standing still all run. A contact with the worker of the
// robot's doing is not asserted here: it happens in lockstep too, in 12 of 200 seeds of this
// mission (the worker coming out from behind the wall beside the door as the robot drives
// through it; docs/navigation.md, "Crossings and lanes"), so three runs would only roll that
// die. It is printed, and measured over the seeds. What varies with the machine (goals reached
// within the run, recoveries, clearances) is printed beside the lockstep run's, which is exact
// and asserted in full.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <thread>
#include <vector>

#include "firmware.hpp"
#include "mission.hpp"
#include "runner.hpp"
#include "sim_rig.hpp"

namespace sen3bot::sim {
namespace {

// One busy thread per CPU at normal priority.
class CpuHog {
 public:
  CpuHog() {
    const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
    for (unsigned c = 0; c < cpus; ++c) {
      threads_.emplace_back([this] {
        volatile std::uint64_t x = 0;
        while (!stop_.load(std::memory_order_relaxed)) x = x * 6364136223846793005ull + 1;
      });
    }
  }
  ~CpuHog() {
    stop_ = true;
    for (auto& t : threads_) t.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

struct Outcome {
  firmware::MissionReport mission;
  RefereeReport truth;
  int robot_hit_map = 0;     // contacts of the robot's doing with the map or a box
  int robot_hit_person = 0;  // with the worker
};

Outcome run_mission(bool lockstep) {
  testing::SimRig rig = testing::load_sim_rig();
  rig.config.clock = lockstep ? firmware::ClockMode::lockstep : firmware::ClockMode::realtime;
  rig.make_board(lockstep);
  std::FILE* out = std::tmpfile();
  EXPECT_NE(out, nullptr);
  firmware::Firmware fw(rig.config, *rig.board, out);
  rig.board->referee().watch_estimate(&fw.pose_estimate());
  const int rc = firmware::run_firmware(fw, *rig.board, rig.config, out, stderr);
  // 3: the mission gave a goal up. The lockstep run must not; a real-time run may, as 3 % of
  // lockstep seeds do (the worker walks into the robot standing in their lane above the door
  // until it gives up; docs/navigation.md, "Measured among two workers"): printed, not failed.
  EXPECT_TRUE(rc == 0 || (!lockstep && rc == 3)) << "exit status " << rc;
  Outcome o;
  if (fw.mission() != nullptr) o.mission = fw.mission()->report();
  o.truth = rig.board->referee().report();
  for (const TimedPose& c : rig.board->referee().contact_poses())
    if (c.moving) ++(c.person ? o.robot_hit_person : o.robot_hit_map);
  std::fclose(out);
  return o;
}

TEST(RealTimeMission, UnderACpuHogIsAsSafeAsTheLockstepRun) {
  const Outcome lockstep = run_mission(true);
  ASSERT_EQ(lockstep.mission.state, firmware::MissionState::complete);
  ASSERT_EQ(lockstep.truth.moving_contacts, 0u);

  constexpr int kRuns = 3;
  std::uint32_t recoveries = 0;
  int complete = 0;
  for (int run = 0; run < kRuns; ++run) {
    Outcome o;
    {
      CpuHog hog;
      o = run_mission(false);
    }
    std::printf("real-time run %d under load: %zu goals, %u recoveries, %llu contacts (%d of the robot's doing "
                "with the worker, %d with the map), min clearance %.2f m, closest person %.2f m (lockstep: %u recoveries)\n",
                run + 1, o.mission.goals_reached, o.mission.recoveries,
                static_cast<unsigned long long>(o.truth.contacts), o.robot_hit_person, o.robot_hit_map,
                o.truth.min_clearance_m, o.truth.min_person_distance_m, lockstep.mission.recoveries);
    EXPECT_EQ(o.robot_hit_map, 0) << "run " << run + 1 << ": the robot drove into the map or a box";
    // Alive in real time: a firmware that stood still would never touch anyone.
    EXPECT_GE(o.mission.goals_reached, 1u) << "run " << run + 1;
    complete += o.mission.state == firmware::MissionState::complete ? 1 : 0;
    recoveries += o.mission.recoveries;
  }
  std::printf("under load: %d of %d runs completed the mission within the run, %.1f recoveries a run (lockstep: %u)\n",
              complete, kRuns, static_cast<double>(recoveries) / kRuns, lockstep.mission.recoveries);
}

}  // namespace
}  // namespace sen3bot::sim
