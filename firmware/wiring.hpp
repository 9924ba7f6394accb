#pragma once
// How the rows are built. Each row of the task table names its factory (task_table.hpp); the
// factory takes the topics its task reads and writes from the Wiring, names the devices it
// talks to and the other rows whose state it reads, and makes the task. The Wiring notes every
// one of those, so the graph `sen3bot graph` prints is the flow the firmware runs.
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/task.hpp"
#include "topics.hpp"

namespace sen3bot::camera {
class Camera;
class FramePool;
}
namespace sen3bot::view {
class Server;
}

namespace sen3bot::firmware {

// What the rows share besides the bus: the Firmware owns it; navigation's map and waypoints
// are loaded before the factories run.
struct Shared {
  nav::OccupancyMap map;
  std::vector<msg::Point2D> waypoints;
  msg::SensorMount laser_mount{};
  camera::FramePool* external_frames = nullptr;  // a simulated camera's
  camera::Camera* camera = nullptr;              // the camera row's, written by its init()
  view::Server* external_view = nullptr;
  const tasks::Topic<msg::People>* external_people = nullptr;  // a simulator's ground truth
};

// One row as its factory declared it.
struct RowWiring {
  std::string_view name;
  std::string absent;  // why this configuration runs no task in the row (empty: it runs one)
  std::vector<std::string> devices;  // "<- ..." what comes in from outside, "-> ..." what goes out
  std::vector<std::string> reads, writes;  // topics
  std::vector<std::string> uses;           // rows whose state it reads directly
};

class Wiring {
 public:
  Wiring(const FirmwareConfig& firmware_config, hal::Board& robot_board, tasks::Bus& event_bus,
         tasks::Scheduler& row_scheduler, std::FILE* text_out, Topics& topics, Shared& shared_state,
         std::span<std::unique_ptr<tasks::Task>> tasks, std::span<RowWiring> rows) noexcept
      : config(firmware_config), board(robot_board), bus(event_bus), scheduler(row_scheduler), out(text_out),
        shared(shared_state), topics_(topics), tasks_(tasks), rows_(rows) {}

  const FirmwareConfig& config;
  hal::Board& board;
  tasks::Bus& bus;
  tasks::Scheduler& scheduler;
  std::FILE* out;
  Shared& shared;

  // The file the configuration came from, for error messages.
  [[nodiscard]] const char* file() const noexcept { return config.source_path.c_str(); }

  template <class T>
  const tasks::Topic<T>& reads(tasks::Topic<T> Topics::*topic) {
    note(row().reads, (topics_.*topic).name());
    return topics_.*topic;
  }
  template <class T>
  tasks::Topic<T>& writes(tasks::Topic<T> Topics::*topic) {
    note(row().writes, (topics_.*topic).name());
    return topics_.*topic;
  }
  template <class T>
  const tasks::Topic<T>* reads_if(bool used, tasks::Topic<T> Topics::*topic) {
    return used ? &reads(topic) : nullptr;
  }
  template <class T>
  tasks::Topic<T>* writes_if(bool used, tasks::Topic<T> Topics::*topic) {
    return used ? &writes(topic) : nullptr;
  }
  // What the row takes in from outside the firmware (a device's bytes, a network peer's
  // messages) and what it sends out.
  void takes(std::string what) { row().devices.push_back("<- " + std::move(what)); }
  void sends(std::string what) { row().devices.push_back("-> " + std::move(what)); }
  // Another row's task, made before this one (earlier in the table), whose state this row
  // reads; null when that row runs none.
  tasks::Task* uses(std::string_view name);
  // Whether an earlier row runs a task (not noted: for a choice of topics).
  [[nodiscard]] bool runs(std::string_view name) const noexcept;

  // This row's task.
  template <class T, class... Args>
  T& make(Args&&... args) {
    auto task = std::make_unique<T>(std::forward<Args>(args)...);
    T& made = *task;
    tasks_[current_] = std::move(task);
    return made;
  }
  void adopt(std::unique_ptr<tasks::Task> task) noexcept { tasks_[current_] = std::move(task); }
  // This configuration runs no task in the row, and why (said when its budget is configured).
  Status absent(std::string why) {
    row().absent = std::move(why);
    return Status::success();
  }

  void begin_row(std::size_t index) noexcept { current_ = index; }

 private:
  RowWiring& row() noexcept { return rows_[current_]; }
  static void note(std::vector<std::string>& list, std::string_view name);

  Topics& topics_;
  std::span<std::unique_ptr<tasks::Task>> tasks_;
  std::span<RowWiring> rows_;
  std::size_t current_ = 0;
};

// The data flow of the rows that run, as text (by thread, then by topic) and as a Mermaid
// flowchart (a figure wherever Markdown is rendered).
void print_graph(std::span<const RowWiring> rows, std::FILE* out);
void print_graph_mermaid(std::span<const RowWiring> rows, std::FILE* out);

}  // namespace sen3bot::firmware
