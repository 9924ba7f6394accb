#pragma once
// The simulated robot for the main job: the map as ground truth with scripted movers, the
// Pioneer (ARCOS) and LMS200 emulators on the far ends of the drivers' byte streams, and the
// bookkeeping a mission report needs (true pose, contacts, clearance).
//
// The firmware does not know it is simulated: SimBoard (sim_board.hpp) hands its drivers the
// emulators' ends as links: in-memory pipes (lockstep: one thread, deterministic for a seed) or
// real pseudo-terminals whose slave paths are opened as serial ports (real time).
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sen3bot/crowd/crowd.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/hal/pty.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/sim/lms200/emulator.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"
#include "sen3bot/sim/sim_detector.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::sim {

enum class LinkKind : std::uint8_t {
  memory,  // in-memory byte pipes, for lockstep simulated time
  pty,     // real pseudo-terminals, for real time
};

// A scripted happening on the simulated CAN I/O node: its inputs change (an e-stop pressed,
// a reset button), it falls silent or talks again, reboots, or the bus goes off or on.
struct SimIoEvent {
  enum class What : std::uint8_t { inputs, silent, talking, reboot, bus_off, bus_on };
  double at_s = 0.0;
  What what = What::inputs;
  std::uint8_t inputs = 0;  // What::inputs: the levels, bit i = input i + 1
};

// The robot's CANopen safety I/O node (the firmware's devices.io_node at interface "sim").
struct SimIoNodeConfig {
  bool enabled = false;
  std::uint8_t node = 0x10;
  std::uint8_t inputs = 0x01;  // levels at power-up: the e-stop chain on input 1 closed
  std::vector<SimIoEvent> events;  // in time order
};

struct SimulationConfig {
  std::string map_path;               // ROS map_server YAML of the ground-truth world
  nav::Pose2D start_pose;             // true pose of the robot at t = 0 (map frame)
  nav::Pose2D laser_mount;            // scanner pose in the robot frame
  nav::Footprint footprint = nav::Footprint::pioneer();
  std::uint64_t seed = 1;             // range noise and fault noise
  double range_noise_sigma_m = 0.01;  // Gaussian noise on each simulated range
  double laser_max_range_m = 8.0;     // beyond this the scanner reports "no echo"
  LinkKind link = LinkKind::memory;
  std::vector<world::MoverScript> movers;  // people and boxes walking polylines
  // A kidnapping: at kidnap_time_s (< 0: never) the robot is carried to kidnap_pose; its
  // odometry is not told.
  double kidnap_time_s = -1.0;
  nav::Pose2D kidnap_pose;
  // Someone pushes the robot with its motors off along these points (map frame) at push_speed
  // (the way a site is often mapped: sim.push); empty: nobody does.
  std::vector<nav::Point2D> push_path;
  double push_speed_m_s = 0.4;
  double push_start_s = 3.0;  // after the robot's start-up, as a person waits for it
  p2os::EmulatorConfig base;
  lms200::EmulatorOptions laser;
  std::size_t pipe_bytes = 16 * 1024;  // per direction, memory links
  SimDetectorConfig detector;          // the remote person detector, off unless configured
  SimIoNodeConfig io_node;             // the CAN I/O node, absent unless configured
  // People moved by a crowd model (recorded, social, blind or ORCA) that may react to the
  // robot: each a world mover with legs, added after `movers`. Null: none.
  std::shared_ptr<const crowd::CrowdConfig> crowd;
};

// What really happened, published every simulation step.
struct GroundTruth {
  hal::Nanos stamp_ns = 0;
  nav::Pose2D pose;                 // true robot pose, map frame
  double speed_m_s = 0;             // true forward speed
  double clearance_m = 0;           // footprint to the nearest obstacle or mover (capped, 20 Hz)
  double nearest_person_m = 0;      // robot centre to the nearest visible person (capped)
  std::uint64_t contacts = 0;       // times the footprint started to overlap something
  std::uint64_t moving_contacts = 0;  // of those, the robot moving towards what it touched
  bool in_contact = false;
  bool contact_person = false;  // the newest contact began with a person
  hal::Nanos kidnapped_ns = -1;     // when the robot was carried away (-1: not yet)
  bool push_done = false;           // the push path's last point was reached
  // The visible people's true centres (the first kMaxPeople of them), for the referee.
  static constexpr std::size_t kMaxPeople = 16;
  std::array<nav::Point2D, kMaxPeople> people{};
  std::array<std::uint32_t, kMaxPeople> people_movers{};  // each one's world mover index
  std::size_t people_count = 0;
  // Cage entries, judged every kCageJudgeS against every person, whatever moves them
  // (judged_cage_reach_m of referee.hpp): the robot's when its own motion since the last
  // judgement closed the distance, else the person's, who stepped up to it.
  std::uint64_t cage_entries = 0;
  std::uint64_t cage_entries_by_person = 0;
  static constexpr double kCageJudgeS = 0.25;
};
static_assert(std::is_trivially_copyable_v<GroundTruth>);

class Simulation {
 public:
  // Loads the map, builds the world and opens the links. Allocates; call before the run.
  static Result<std::unique_ptr<Simulation>> create(const SimulationConfig& config);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // The drivers' ends. Memory links: the streams and the laser's line; pty links: the slave
  // device paths (open them as serial ports).
  [[nodiscard]] hal::ByteStream* base_driver_stream() noexcept;
  [[nodiscard]] hal::ByteStream* laser_driver_stream() noexcept;
  [[nodiscard]] lms200::LineControl* laser_driver_line() noexcept;
  [[nodiscard]] std::string base_device_path() const;
  [[nodiscard]] std::string laser_device_path() const;

  // Advances the world to `now` and lets both emulators read and answer. Never allocates.
  void step(hal::Nanos now_ns) noexcept;
  [[nodiscard]] const GroundTruth& truth() const noexcept { return truth_; }

  [[nodiscard]] world::World& world() noexcept { return *world_; }
  // The crowd's people are the world's movers from this index on (none without a crowd).
  [[nodiscard]] std::size_t first_crowd_mover() const noexcept { return first_crowd_mover_; }
  [[nodiscard]] const crowd::Crowd* crowd() const noexcept { return crowd_.get(); }
  [[nodiscard]] p2os::P2osEmulator& base() noexcept { return base_; }
  [[nodiscard]] lms200::Lms200Emulator& laser() noexcept { return *laser_; }
  [[nodiscard]] const SimulationConfig& config() const noexcept { return config_; }

 private:
  class WorldRanges;
  class WorldObstacles;
  class PtyLine;

  explicit Simulation(const SimulationConfig& config);
  Status open(const nav::OccupancyMap& map);
  void place_crowd(hal::Nanos now_ns) noexcept;

  SimulationConfig config_;
  std::unique_ptr<world::World> world_;
  std::unique_ptr<crowd::Crowd> crowd_;
  std::size_t first_crowd_mover_ = 0;
  std::unique_ptr<WorldRanges> ranges_;
  std::unique_ptr<WorldObstacles> obstacles_;
  p2os::P2osEmulator base_;
  std::size_t push_next_ = 0;  // the push path's point being pushed towards
  std::unique_ptr<lms200::Lms200Emulator> laser_;
  // Memory links.
  std::unique_ptr<hal::MemoryPipe> base_pipe_;
  std::unique_ptr<hal::MemoryPipe> laser_pipe_;
  std::unique_ptr<lms200::SimulatedLine> laser_line_;
  // Pty links.
  std::unique_ptr<hal::PtyPair> base_pty_;
  std::unique_ptr<hal::PtyPair> laser_pty_;
  std::unique_ptr<PtyLine> laser_pty_line_;
  GroundTruth truth_;
  hal::Nanos next_clearance_ns_ = 0;
  void judge_cages(const nav::Pose2D& pose) noexcept;
  void push(const nav::Pose2D& pose) noexcept;
  hal::Nanos next_cage_judge_ns_ = 0;
  bool cage_judged_ = false;
  nav::Pose2D cage_judged_pose_;
  std::vector<bool> in_cage_;  // per mover, at the last judgement (sized at open)
};

}  // namespace sen3bot::sim
