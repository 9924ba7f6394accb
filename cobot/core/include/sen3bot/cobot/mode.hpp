#pragma once
// The robot's collaboration mode (fleet.md, "Sen3CoBot collaboration trigger"): cooperative
// (its own or the fleet's task), wait4col (standing idle in a sub-critical area, waiting for
// an operator) and collaborative (following its operator). The trigger's requests switch it;
// where the robot stands decides whether it may wait at all. Pure: no clock, no I/O.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/cobot/trigger.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/static_vector.hpp"
#include "sen3bot/msg/cobot.hpp"

namespace sen3bot::cobot {

// The site's area the robot stands in (the caller decides from the site's polygons; where
// areas overlap, a type-1 area wins).
enum class AreaType : std::uint8_t {
  none,             // in no area of the site
  critical_1_1,     // type 1: always cooperative
  critical_1_2,
  sub_critical_2,   // type 2: collaboration allowed
  not_monitored_3,  // type 3
};
[[nodiscard]] const char* to_string(AreaType area) noexcept;

struct ModeConfig {
  bool wait4col_enabled = true;  // an idle robot in a type-2 area offers itself to operators
};

enum class ModeEventKind : std::uint8_t {
  entered_wait4col,  // idle in a type-2 area: waiting for an operator
  left_wait4col,     // a cooperative goal came, or the robot left the type-2 area
  toggled_on,        // an operator's request: collaborative with them
  toggled_off,       // the same operator's request again: back to cooperative, task resumed
  aborted,           // collaborative outside a type-2 area: back to cooperative, task resumed
  refused,           // a request that cannot be taken now (see ModeRefusal)
};
[[nodiscard]] const char* to_string(ModeEventKind kind) noexcept;

enum class ModeRefusal : std::uint8_t {
  not_the_operator,  // a request by another operator while collaborative
  not_waiting,       // a request while cooperative (the trigger should not have been armed)
};
inline constexpr std::size_t kModeRefusalCount = 2;

struct ModeEvent {
  ModeEventKind kind = ModeEventKind::entered_wait4col;
  ModeRefusal refusal = ModeRefusal::not_the_operator;  // for refused
  std::uint32_t operator_id = 0;
  hal::Nanos stamp_ns = 0;
};

struct ModeInput {
  hal::Nanos now_ns = 0;
  AreaType area = AreaType::none;
  // No cooperative goal, or it was reached, and the robot stands still.
  bool idle = false;
  std::span<const TriggerEvent> trigger_events;  // this cycle's, in order
};

struct ModeOutput {
  static constexpr std::size_t kMaxEvents = 8;
  msg::CobotMode mode = msg::CobotMode::cooperative;
  std::uint32_t operator_id = 0;  // collaborative: whose robot it is (0: none)
  // The cooperative task resumes this cycle (toggled off or aborted): the caller, which kept
  // the goal, drives to it again.
  bool resume = false;
  mem::StaticVector<ModeEvent, kMaxEvents> events;
};

class CollaborationMode {
 public:
  Status init(const ModeConfig& config) noexcept;
  ModeOutput update(const ModeInput& input) noexcept;
  void reset() noexcept;  // cooperative, no operator (the counts stay)

  [[nodiscard]] msg::CobotMode mode() const noexcept { return mode_; }
  [[nodiscard]] std::uint32_t operator_id() const noexcept { return operator_; }
  // Whether the trigger should take requests now (its armed input).
  [[nodiscard]] bool accepts_requests() const noexcept { return mode_ != msg::CobotMode::cooperative; }
  [[nodiscard]] std::uint32_t toggles() const noexcept { return toggles_; }
  [[nodiscard]] std::uint32_t aborts() const noexcept { return aborts_; }
  [[nodiscard]] std::uint32_t refusals(ModeRefusal refusal) const noexcept {
    return refusals_[static_cast<std::size_t>(refusal)];
  }

 private:
  void emit(ModeOutput& out, ModeEventKind kind, std::uint32_t id, hal::Nanos stamp_ns,
            ModeRefusal refusal = ModeRefusal::not_the_operator) noexcept;

  ModeConfig config_;
  msg::CobotMode mode_ = msg::CobotMode::cooperative;
  std::uint32_t operator_ = 0;
  std::uint32_t toggles_ = 0;
  std::uint32_t aborts_ = 0;
  std::array<std::uint32_t, kModeRefusalCount> refusals_{};
};

}  // namespace sen3bot::cobot
