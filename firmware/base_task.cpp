#include "base_task.hpp"

#include <new>
#include <numbers>

#include "adapters.hpp"
#include "sen3bot/p2os/sonar.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

BaseTask::BaseTask(const p2os::P2osConfig& config, hal::Board& board, const BaseTopics& topics)
    : config_(config), board_(board), topics_(topics), backoff_(config.reopen_delay_ms) {
  // The P3-DX's ring (the driver speaks to a P3-DX); never read until a SIP brings a disc.
  sonar_.count = static_cast<std::uint8_t>(p2os::kSonarDiscs);
  sonar_.max_range_m = p2os::kSonarMaxRangeM;
  for (std::size_t d = 0; d < p2os::kSonarDiscs; ++d) {
    const p2os::SonarMount& m = p2os::kP3dxSonar[d];
    sonar_.mount[d] = {m.x_mm / 1000.0, m.y_mm / 1000.0, m.heading_deg * std::numbers::pi / 180.0};
    sonar_.stamp_ns[d] = -1;
  }
}

BaseTask::~BaseTask() {
  if (driver_ != nullptr) {
    driver_->detach();
    driver_->~P2osDriver();
    arena_->deallocate(driver_, sizeof(p2os::P2osDriver), alignof(p2os::P2osDriver));
  }
}

Status BaseTask::init(std::pmr::memory_resource& arena) {
  if (driver_ != nullptr) return Error(Errc::invalid_argument, "base task: init called twice");
  try {
    void* memory = arena.allocate(sizeof(p2os::P2osDriver), alignof(p2os::P2osDriver));
    driver_ = new (memory) p2os::P2osDriver(config_);
    arena_ = &arena;
  } catch (const std::bad_alloc&) {
    return Error::format(Errc::capacity, "base task: the driver needs %zu bytes of arena", sizeof(p2os::P2osDriver));
  }
  try_open(config_.connect_timeout_ms, board_.clock().now());
  return Status::success();
}

void BaseTask::try_open(int connect_timeout_ms, hal::Nanos now_ns) {
  Result<hal::Link> opened = board_.open_link("base", hal::LinkRequest{config_.port, config_.baud, connect_timeout_ms});
  if (!opened) {
    open_error_ = opened.error();
    missing_.store(true, std::memory_order_relaxed);
    backoff_.failed(now_ns);
    return;
  }
  open_error_.reset();
  missing_.store(false, std::memory_order_relaxed);
  link_ = std::move(*opened);
  driver_->attach(*link_.stream, now_ns, link_.baud_control, link_.baud);
}

void BaseTask::publish(hal::Nanos now_ns) {
  const p2os::BaseState& state = driver_->state();
  topics_.odometry.publish(to_nav_odometry(state), now_ns);
  topics_.flags.publish(to_base_flags(state), now_ns);
  last_published_link_ = state.link;
  const p2os::Sip& sip = driver_->last_sip();
  if (topics_.sonar == nullptr || sip.sonar_count == 0) return;
  // Each reading is the newest of its disc; a SIP carries only the discs fired since the last.
  for (std::size_t i = 0; i < std::min<std::size_t>(sip.sonar_count, p2os::kMaxSonarPerSip); ++i) {
    const p2os::SonarReading& r = sip.sonar[i];
    if (r.disc >= sonar_.count) continue;
    sonar_.range_m[r.disc] = r.range_mm * config_.conversion.range_conv_mm_per_unit / 1000.0;
    sonar_.stamp_ns[r.disc] = now_ns;
  }
  topics_.sonar->publish(sonar_, now_ns);
}

void BaseTask::step(const tasks::StepContext& context) {
  if (driver_ == nullptr) return;
  const hal::Nanos now_ns = context.start_ns;
  tasks::Sample<msg::VelocityCommand> command;
  if (topics_.command.read(command) && command.sequence != last_command_sequence_) {
    last_command_sequence_ = command.sequence;
    driver_->set_setpoint(p2os::BaseSetpoint{command.value.v_m_s, command.value.w_rad_s, true}, now_ns);
  }
  if (!driver_->attached() && !driver_->closed()) {
    if (link_.stream) {
      // The stream failed: drop it and try again after the backoff delay.
      open_error_ = driver_->stream_error();
      link_ = hal::Link{};
      missing_.store(true, std::memory_order_relaxed);
      backoff_.failed(now_ns);
    }
    if (backoff_.due(now_ns)) try_open(config_.reopen_connect_timeout_ms, now_ns);
  }
  driver_->step(now_ns);
  // Only a link that reached SIPs resets the backoff: a port that opens and drops at once
  // is still retried slowly.
  if (driver_->state().link == p2os::LinkState::connected) backoff_.succeeded();
  if (driver_->take_new_sip() || driver_->state().link != last_published_link_) publish(now_ns);
}

void BaseTask::shutdown() {
  if (driver_ == nullptr || !driver_->attached()) return;
  hal::Clock& clock = board_.clock();
  driver_->request_close(clock.now());
  const hal::Nanos give_up_ns = clock.now() + hal::seconds(1);
  while (!driver_->closed() && driver_->attached() && clock.now() < give_up_ns) {
    driver_->step(clock.now());
    clock.sleep_until(clock.now() + hal::millis(2));
  }
  publish(clock.now());
}

Status make_base(Wiring& w) {
  if (!w.config.devices.has_base) return w.absent("needs devices.base");
  const p2os::P2osConfig& base = w.config.devices.base;
  w.takes("P2OS server information packets on " + base.port + " (odometry, motor and bumper flags, sonar)");
  w.sends("P2OS commands: VEL2/RVEL from the command, the watchdog's PULSE");
  w.make<BaseTask>(base, w.board,
                   BaseTopics{w.reads(&Topics::command), w.writes(&Topics::odometry), w.writes(&Topics::base_flags),
                              w.writes_if(true, &Topics::sonar)});
  return Status::success();
}

}  // namespace sen3bot::firmware
