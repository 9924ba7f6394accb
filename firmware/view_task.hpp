#pragma once
// The live view's row: on the background thread it reads what the robot sees and decides (the
// bus's topics, and the planner's and mission's state, which run on the same thread), encodes
// each channel that is due as a Foxglove JSON message into the server's board, and wakes the
// server's thread. Every buffer it writes into is taken at init(); a step allocates nothing.
#include <array>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <span>

#include "camera_task.hpp"
#include "mission.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"
#include "sen3bot/view/foxglove.hpp"
#include "sen3bot/view/jpeg.hpp"
#include "sen3bot/view/server.hpp"
#include "view_config.hpp"

namespace sen3bot::firmware {

// What the view reads; a null source leaves its channel out.
struct ViewSources {
  const tasks::Scheduler& scheduler;
  const hal::Clock& clock;
  const nav::OccupancyMap* map = nullptr;
  const tasks::Topic<msg::ScanMessage>* scan = nullptr;
  const tasks::Topic<msg::Odometry>* odometry = nullptr;
  const tasks::Topic<msg::PoseEstimate>* pose = nullptr;
  const tasks::Topic<msg::PathMessage>* path = nullptr;
  const tasks::Topic<msg::VelocityCommand>* request = nullptr;  // the local planner's choice
  const tasks::Topic<msg::SafetyOutput>* safety = nullptr;
  const tasks::Topic<msg::ControllerStatus>* controller = nullptr;
  const tasks::Topic<msg::MovingObstacles>* movers = nullptr;
  const tasks::Topic<msg::People>* people = nullptr;
  const tasks::Topic<msg::CostmapSnapshot>* local_costmap = nullptr;
  const nav::PlannerTask* planner = nullptr;  // same thread: its costmap and safe path
  const MissionTask* mission = nullptr;       // same thread
  std::size_t goal_count = 0;
  FrameSource frames{};  // the camera row's (found at init) or a given pool
  msg::SensorMount laser_mount{};
  double rollout_s = 1.5;  // the DWA's simulated time
};

class ViewTask final : public tasks::Task {
 public:
  // With `server` the task publishes into a server that someone else owns and runs (the
  // simulator keeps one across its cases); without, init() creates and starts its own in the
  // arena.
  ViewTask(const ViewTaskConfig& config, const ViewSources& sources, view::Server* server = nullptr) noexcept;
  ~ViewTask() override;
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  void shutdown() override;

  [[nodiscard]] view::Server* server() noexcept { return server_; }
  // Messages that did not fit their channel's buffer (none expected: each is sized at init).
  [[nodiscard]] std::uint64_t oversized() const noexcept { return oversized_; }

  // What decides the channels and their sizes.
  struct Shape {
    std::size_t map_cells = 0;  // the map's, which the global costmap shares
    bool navigation = false;
    bool scan = false;
    bool camera = false;
  };
  static Shape shape_of(const ViewSources& sources) noexcept;
  // The channels served, with their buffer sizes (also for a server made elsewhere).
  static std::size_t channel_specs(const ViewTaskConfig& config, const Shape& shape,
                                   std::span<view::ChannelSpec, kViewChannels> out) noexcept;

 private:
  struct Scratch;
  bool encode(ViewChannel channel, hal::Nanos now);
  // encode()'s channels but the map and the global costmap, which it writes itself; `stamp` is
  // the step's time on the messages' clock.
  bool encode_local_costmap(std::size_t ch);
  bool encode_scan(std::size_t ch);
  bool encode_tf(std::size_t ch, hal::Nanos stamp);
  bool encode_plan(std::size_t ch);
  bool encode_safe_path(std::size_t ch, hal::Nanos stamp);
  bool encode_driven_path(std::size_t ch, hal::Nanos stamp);
  bool encode_dwa(std::size_t ch);
  bool encode_people(std::size_t ch, hal::Nanos stamp);
  bool encode_camera(std::size_t ch);
  bool encode_stats(std::size_t ch, hal::Nanos stamp, hal::Nanos now);
  bool encode_mission(std::size_t ch, hal::Nanos stamp);
  bool write(std::size_t board_channel, hal::Nanos stamp, auto&& body);

  ViewTaskConfig config_;
  ViewSources sources_;
  view::Server* server_;
  std::unique_ptr<view::Server> own_server_;
  std::array<int, kViewChannels> board_channel_{};  // -1: not served
  std::array<hal::Nanos, kViewChannels> next_ns_{};
  Scratch* scratch_ = nullptr;
  camera::FramePool* frames_ = nullptr;
  std::uint64_t oversized_ = 0;
  hal::Nanos start_ns_ = 0;
};

}  // namespace sen3bot::firmware
