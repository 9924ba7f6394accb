#include "can_io_task.hpp"

#include <cmath>

#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

namespace {

constexpr std::uint8_t bit(std::uint8_t number) noexcept {
  return number == 0 ? std::uint8_t{0} : static_cast<std::uint8_t>(1u << (number - 1));
}

}  // namespace

Status check(const CanIoConfig& c) {
  if (Status s = canopen::IoNodeMaster::check(c.master); !s) return s;
  if (c.interface.empty()) return Error(Errc::config, "interface: missing");
  if (c.estop_input < 1 || c.estop_input > 8) return Error(Errc::config, "inputs.estop: expected an input 1..8");
  if (c.reset_input > 8) return Error(Errc::config, "inputs.reset: expected an input 1..8 (or 0: none)");
  if (c.reset_input == c.estop_input)
    return Error(Errc::config, "inputs.reset: the e-stop chain's input cannot also be the reset");
  if ((c.bumper_inputs & (bit(c.estop_input) | bit(c.reset_input))) != 0)
    return Error(Errc::config, "inputs.bumpers: an input is already the e-stop chain or the reset");
  std::uint8_t used = 0;
  const auto claim = [&](std::uint8_t output, const char* key) -> Status {
    if (output > 8) return Error::format(Errc::config, "outputs.%s: expected an output 1..8 (or 0: none)", key);
    if ((used & bit(output)) != 0) return Error::format(Errc::config, "outputs.%s: output %u is used twice", key, output);
    used = static_cast<std::uint8_t>(used | bit(output));
    return Status::success();
  };
  for (std::size_t m = 1; m < c.light_outputs.size(); ++m)
    if (Status s = claim(c.light_outputs[m], msg::to_string(static_cast<msg::LightMode>(m))); !s) return s;
  if (Status s = claim(c.buzzer_output, "buzzer"); !s) return s;
  if (!(c.buzzer_period_s > 0.0)) return Error(Errc::config, "outputs.buzzer_period_s: must be positive");
  if (!(c.driving_hold_s > 0.0)) return Error(Errc::config, "driving_hold_s: must be positive");
  return Status::success();
}

msg::LightMode light_mode(std::uint32_t reasons, bool moving, bool wait4col) noexcept {
  constexpr std::uint32_t kFault =
      msg::kSafetyEstop | msg::kSafetyEstopChain | msg::kSafetyBumper | msg::kSafetyIoLost | msg::kSafetyResetNeeded;
  if ((reasons & kFault) != 0) return msg::LightMode::fault;
  if (moving) return msg::LightMode::driving;
  if (wait4col) return msg::LightMode::wait4col;
  return msg::LightMode::idle;
}

std::uint8_t output_levels(const CanIoConfig& config, msg::LightMode mode, bool buzzer_on) noexcept {
  std::uint8_t levels = bit(config.light_outputs[static_cast<std::size_t>(mode)]);
  if (buzzer_on) levels = static_cast<std::uint8_t>(levels | bit(config.buzzer_output));
  return levels;
}

CanIoTask::CanIoTask(const CanIoConfig& config, hal::Board& board, const CanIoTopics& topics)
    : config_(config), board_(board), topics_(topics), master_(config.master) {}

CanIoTask::~CanIoTask() = default;

Status CanIoTask::init(std::pmr::memory_resource& /*arena*/) {
  if (Status s = check(config_); !s) return Error::format(s.error().code(), "devices.io_node.%s", s.error().c_str());
  Result<std::unique_ptr<hal::CanBus>> bus = board_.open_can("io_node", config_.interface);
  if (!bus) return bus.error();
  bus_ = std::move(*bus);
  // Only the node's own frames: its EMCY, TPDO1, SDO answers and heartbeat.
  const std::uint32_t node = config_.master.node;
  const hal::CanFilter filters[] = {
      {0x080 + node, 0x7FF, hal::CanFilter::Format::standard},
      {0x180 + node, 0x7FF, hal::CanFilter::Format::standard},
      {0x580 + node, 0x7FF, hal::CanFilter::Format::standard},
      {0x700 + node, 0x7FF, hal::CanFilter::Format::standard},
  };
  return bus_->set_filters(filters);
}

void CanIoTask::step(const tasks::StepContext& context) {
  const hal::Nanos now = context.start_ns;
  bool bus_ok = true;
  for (std::size_t i = 0; i < kMaxFramesPerStep; ++i) {
    Result<std::optional<hal::CanFrame>> frame = bus_->receive();
    if (!frame) {
      ++bus_errors_;
      bus_ok = false;
      break;
    }
    if (!frame->has_value()) break;
    master_.on_frame(**frame, now);
  }

  // The light shows the newest decisions of the safety task and the collaborative mode.
  tasks::Sample<msg::SafetyOutput> safety;
  const std::uint32_t reasons = topics_.safety.read(safety) ? safety.value.reasons : msg::kSafetyNone;
  tasks::Sample<msg::VelocityCommand> command;
  const bool moving = topics_.command.read(command) &&
                      static_cast<double>(now - command.stamp_ns) <= config_.driving_hold_s * 1e9 &&
                      (command.value.v_m_s != 0.0 || command.value.w_rad_s != 0.0);
  tasks::Sample<msg::OperatingMode> mode;
  const bool wait4col = topics_.mode != nullptr && topics_.mode->read(mode) && mode.value.wait4col;
  light_ = light_mode(reasons, moving, wait4col);
  const double period_ns = config_.buzzer_period_s * 1e9;
  const bool buzzer_on =
      light_ == msg::LightMode::fault && std::fmod(static_cast<double>(now), period_ns) < period_ns / 2.0;
  master_.set_outputs(output_levels(config_, light_, buzzer_on));

  // Frames the controller refused last cycle go first (SocketCAN's bounded queue).
  if (Status s = bus_->flush(); !s && s.error().code() != Errc::would_block) ++bus_errors_;
  std::array<hal::CanFrame, 4> out;
  const std::size_t n = master_.poll(now, out);
  for (std::size_t i = 0; i < n; ++i) {
    if (Status s = bus_->send(out[i]); !s) {
      if (s.error().code() == Errc::would_block) ++send_drops_;
      else ++bus_errors_;
    }
  }

  const bool valid = master_.inputs_valid() && bus_ok && bus_->link_state() != hal::CanLinkState::bus_off;
  const std::uint8_t inputs = master_.inputs();
  io_.healthy = valid;
  io_.ever_healthy = io_.ever_healthy || valid;
  io_.inputs = inputs;
  io_.outputs = master_.outputs();
  io_.inputs_ns = master_.inputs_ns();
  if (valid) {
    const bool chain_high = (inputs & bit(config_.estop_input)) != 0;
    io_.estop = config_.estop_active_low ? !chain_high : chain_high;
    const std::uint8_t bumpers = config_.bumpers_active_low ? static_cast<std::uint8_t>(~inputs) : inputs;
    io_.bumper = (bumpers & config_.bumper_inputs) != 0;
    const bool reset = config_.reset_input != 0 && (inputs & bit(config_.reset_input)) != 0;
    if (reset && !reset_level_) ++io_.resets;
    reset_level_ = reset;
  }
  topics_.io.publish(io_, now);
}

Status make_can_io(Wiring& w) {
  if (!w.config.devices.has_io_node) return w.absent("needs devices.io_node");
  const CanIoConfig& io = w.config.devices.io_node;
  w.takes("CANopen frames on " + io.interface + " from node " + std::to_string(io.master.node) +
          ": inputs (e-stop chain, reset, bumpers) by TPDO, heartbeat");
  w.sends("CANopen RPDO to the node's outputs (status light), NMT, SDO set-up");
  w.make<CanIoTask>(io, w.board,
                    CanIoTopics{w.reads(&Topics::safety_output), w.reads(&Topics::command), w.writes(&Topics::safety_io),
                                w.reads_if(w.config.cobot.enabled && w.config.navigation.enabled, &Topics::operating_mode)});
  return Status::success();
}

}  // namespace sen3bot::firmware
