#include "sen3bot/cobot/mode.hpp"

namespace sen3bot::cobot {

const char* to_string(AreaType area) noexcept {
  switch (area) {
    case AreaType::none: return "none";
    case AreaType::critical_1_1: return "critical_1_1";
    case AreaType::critical_1_2: return "critical_1_2";
    case AreaType::sub_critical_2: return "sub_critical_2";
    case AreaType::not_monitored_3: return "not_monitored_3";
  }
  return "unknown";
}

const char* to_string(ModeEventKind kind) noexcept {
  switch (kind) {
    case ModeEventKind::entered_wait4col: return "entered_wait4col";
    case ModeEventKind::left_wait4col: return "left_wait4col";
    case ModeEventKind::toggled_on: return "toggled_on";
    case ModeEventKind::toggled_off: return "toggled_off";
    case ModeEventKind::aborted: return "aborted";
    case ModeEventKind::refused: return "refused";
  }
  return "unknown";
}

Status CollaborationMode::init(const ModeConfig& config) noexcept {
  config_ = config;
  reset();
  return Status::success();
}

void CollaborationMode::reset() noexcept {
  mode_ = msg::CobotMode::cooperative;
  operator_ = 0;
}

void CollaborationMode::emit(ModeOutput& out, ModeEventKind kind, std::uint32_t id, hal::Nanos stamp_ns,
                             ModeRefusal refusal) noexcept {
  ModeEvent event;
  event.kind = kind;
  event.refusal = refusal;
  event.operator_id = id;
  event.stamp_ns = stamp_ns;
  (void)out.events.push_back(event);  // a full list drops the event; the counts keep it
}

ModeOutput CollaborationMode::update(const ModeInput& input) noexcept {
  ModeOutput out;
  const bool in_type_2 = input.area == AreaType::sub_critical_2;

  // Where the robot stands first: a request read in the same cycle as a goal came, or as the
  // robot left the area, finds it no longer waiting.
  switch (mode_) {
    case msg::CobotMode::cooperative: break;
    case msg::CobotMode::wait4col:
      if (!in_type_2 || !input.idle || !config_.wait4col_enabled) {
        mode_ = msg::CobotMode::cooperative;
        emit(out, ModeEventKind::left_wait4col, 0, input.now_ns);
      }
      break;
    case msg::CobotMode::collaborative:
      // Follow-me keeps the robot inside its type-2 area; a pose that says otherwise (a
      // type-1 area, or out of the area) ends the collaboration.
      if (!in_type_2) {
        ++aborts_;
        emit(out, ModeEventKind::aborted, operator_, input.now_ns);
        mode_ = msg::CobotMode::cooperative;
        operator_ = 0;
        out.resume = true;
      }
      break;
  }

  for (const TriggerEvent& event : input.trigger_events) {
    if (event.kind != TriggerEventKind::request) continue;
    switch (mode_) {
      case msg::CobotMode::wait4col:
        mode_ = msg::CobotMode::collaborative;
        operator_ = event.operator_id;
        ++toggles_;
        emit(out, ModeEventKind::toggled_on, operator_, event.stamp_ns);
        break;
      case msg::CobotMode::collaborative:
        if (event.operator_id == operator_) {
          ++toggles_;
          emit(out, ModeEventKind::toggled_off, operator_, event.stamp_ns);
          mode_ = msg::CobotMode::cooperative;
          operator_ = 0;
          out.resume = true;
        } else {
          ++refusals_[static_cast<std::size_t>(ModeRefusal::not_the_operator)];
          emit(out, ModeEventKind::refused, event.operator_id, event.stamp_ns, ModeRefusal::not_the_operator);
        }
        break;
      case msg::CobotMode::cooperative:
        ++refusals_[static_cast<std::size_t>(ModeRefusal::not_waiting)];
        emit(out, ModeEventKind::refused, event.operator_id, event.stamp_ns, ModeRefusal::not_waiting);
        break;
    }
  }

  // A robot that has just toggled off or aborted goes back to its task this cycle; it may
  // offer itself again from the next one.
  if (mode_ == msg::CobotMode::cooperative && !out.resume && config_.wait4col_enabled && in_type_2 && input.idle) {
    mode_ = msg::CobotMode::wait4col;
    emit(out, ModeEventKind::entered_wait4col, 0, input.now_ns);
  }

  out.mode = mode_;
  out.operator_id = operator_;
  return out;
}

}  // namespace sen3bot::cobot
