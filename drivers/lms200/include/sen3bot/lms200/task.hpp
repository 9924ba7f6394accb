#pragma once
// The LMS200 as a periodic task: init() opens the port (or takes a stream from the caller) and
// takes its memory from the task's arena; step() drives the device state machine and
// publishes each new scan on a Topic. step() never allocates or blocks.
#include <memory_resource>

#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/lms200/scan.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::lms200 {

// LineControl for a real serial port; tells a capture recorder about each switch.
class SerialLineControl final : public LineControl {
 public:
  explicit SerialLineControl(hal::SerialPort& port, capture::RecordingStream* recorder = nullptr) noexcept
      : port_(port), recorder_(recorder) {}
  Status set_baud(std::uint32_t baud) override {
    Status s = port_.set_baud(baud);
    if (s && recorder_ != nullptr) recorder_->note_baud_change(baud);
    return s;
  }

 private:
  hal::SerialPort& port_;
  capture::RecordingStream* recorder_;
};

class Lms200Task final : public tasks::Task {
 public:
  // Opens config.port in init() with hal::open_byte_stream.
  Lms200Task(const Lms200Config& config, tasks::Topic<LaserScan>& topic);
  // Talks over a stream the caller owns (simulation, replay, tests); `line` may be null.
  Lms200Task(const Lms200Config& config, hal::ByteStream& stream, LineControl* line, tasks::Topic<LaserScan>& topic);
  ~Lms200Task() override;

  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // Clean stop (20 25, back to 9600) when the task owns a real port; bounded to ~2 s.
  void shutdown() override;

  // Null before init().
  [[nodiscard]] const Lms200Device* device() const noexcept { return device_; }
  // Arena bytes init() needs, for sizing the task's budget.
  static constexpr std::size_t kArenaBytes = sizeof(Lms200Device) + sizeof(LaserScan) + 256;

 private:
  Lms200Config config_;
  tasks::Topic<LaserScan>& topic_;
  hal::ByteStream* external_stream_ = nullptr;
  LineControl* external_line_ = nullptr;
  std::unique_ptr<hal::ByteStream> owned_stream_;
  std::unique_ptr<SerialLineControl> owned_line_;
  std::pmr::memory_resource* arena_ = nullptr;
  Lms200Device* device_ = nullptr;
  LaserScan* scan_ = nullptr;
  hal::Nanos next_reopen_ns_ = 0;
  bool started_ = false;
};

}  // namespace sen3bot::lms200
