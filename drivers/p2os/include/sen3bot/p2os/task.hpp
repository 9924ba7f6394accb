#pragma once
// P2osTask: the base driver as a scheduler task. Reads BaseSetpoint from a topic, steps the
// driver, publishes BaseState after every SIP (and on link changes), and reopens the port
// after it failed.
#include <functional>
#include <memory>
#include <memory_resource>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "sen3bot/p2os/types.hpp"

namespace sen3bot::p2os {

// Opens the link; the default uses hal::open_byte_stream(config.port, config.baud).
// Returns the stream and, for a serial port, something that can change its rate.
struct OpenedLink {
  std::unique_ptr<hal::ByteStream> stream;
  BaudControl* baud_control = nullptr;  // points into `stream`'s owner, or null
  std::uint32_t baud = 0;               // rate it was opened at, 0 if not serial
};
using LinkOpener = std::function<Result<OpenedLink>(const P2osConfig&)>;
Result<OpenedLink> open_p2os_link(const P2osConfig& config);

class P2osTask final : public tasks::Task {
 public:
  P2osTask(const P2osConfig& config, hal::Clock& clock, tasks::Topic<BaseSetpoint>& setpoint_topic,
           tasks::Topic<BaseState>& state_topic, LinkOpener opener = open_p2os_link);
  ~P2osTask() override;

  // Builds the driver in `arena` and opens the port (a failed open is retried in step()).
  Status init(std::pmr::memory_resource& arena) override;
  // Does not allocate or block in steady state. Reopening a failed link allocates a new stream
  // object and, for TCP, may block up to reopen_connect_timeout_ms; it happens at most once per
  // reopen_delay_ms.
  void step(const tasks::StepContext& context) override;
  // Zero velocity, ENABLE 0, CLOSE; waits up to one second for them to go out.
  void shutdown() override;

  [[nodiscard]] const P2osDriver* driver() const noexcept { return driver_; }
  [[nodiscard]] const std::optional<Error>& last_open_error() const noexcept { return open_error_; }

 private:
  void try_open(const P2osConfig& config, hal::Nanos now_ns);

  P2osConfig config_;
  P2osConfig reopen_config_;  // config_ with the short reopen connect timeout
  hal::Clock& clock_;
  tasks::Topic<BaseSetpoint>& setpoint_topic_;
  tasks::Topic<BaseState>& state_topic_;
  LinkOpener opener_;
  std::pmr::memory_resource* arena_ = nullptr;
  P2osDriver* driver_ = nullptr;
  OpenedLink link_;
  std::optional<Error> open_error_;
  hal::Nanos next_open_ns_ = 0;
  std::uint64_t last_setpoint_sequence_ = 0;
  LinkState last_published_link_ = LinkState::disconnected;
};

}  // namespace sen3bot::p2os
