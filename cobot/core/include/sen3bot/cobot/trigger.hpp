#pragma once
// The operator's request sequence (fleet.md, "Sen3CoBot collaboration trigger"): a trained
// operator stands in front of the robot showing the front tag of the leg band for T_f, turns,
// and shows the back tag for T_b. The trigger reads the tags of each camera frame and the
// people tracker's view of the operator each control cycle, and reports a completed request
// or a refused attempt with its reason. docs/cobot/collaboration.md gives the state machine.
//
// Times are the frames' capture times (TagFrame::capture_ns, firmware clock): a phase lasts
// from its first sighting to its last, and two sightings of a tag at most
// max_sighting_gap_s apart belong to one continuous showing. Durations and gaps are compared
// in whole nanoseconds, inclusive at both ends of every window. Pure: no clock, no I/O, no
// allocation.
#include <array>
#include <cstddef>
#include <cstdint>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/static_vector.hpp"
#include "sen3bot/msg/cobot.hpp"

namespace sen3bot::cobot {

struct TriggerConfig {
  static constexpr std::size_t kMaxOperators = 32;
  double min_distance_m = 0.5;  // the operator's distance from the laser while showing, D_f
  double max_distance_m = 1.0;
  double front_min_s = 2.0;  // T_f: first to last front sighting
  double front_max_s = 3.0;
  double back_min_s = 2.0;   // T_b: first to last back sighting
  double back_max_s = 3.0;
  double max_turn_s = 2.5;   // last front sighting to first back sighting
  // Sightings of one tag at most this far apart are one continuous showing (the reader misses
  // a frame or two at 5 Hz while the tag is shown).
  double max_sighting_gap_s = 0.7;
  // How late a frame may reach the trigger after it was taken: silence is judged from the
  // clock only this long after it would be from the frames, so a frame still on its way does
  // not end a phase.
  double max_frame_delay_s = 0.2;
  // T_f counts from when the operator stands: while they walk up with the front tag towards
  // the robot (faster than this), the front phase keeps starting again.
  double standing_speed_m_s = 0.25;
  mem::StaticVector<std::uint32_t, kMaxOperators> operators;  // the trained operators' tag ids
};

enum class TriggerPhase : std::uint8_t {
  idle,      // no attempt under way (showings that start none are watched, see below)
  front,     // the operator shows the front tag
  turning,   // the front showing ended; waiting for the back tag (a short front no back
             // follows within max_turn_s was a glimpse: back to idle, nothing refused)
  back,      // the operator shows the back tag
  cooldown,  // an attempt ended; the rest of its showing and turn is ignored
};
[[nodiscard]] const char* to_string(TriggerPhase phase) noexcept;

enum class TriggerRejection : std::uint8_t {
  too_near,           // the operator nearer than min_distance_m at a sighting
  too_far,            // farther than max_distance_m at a sighting
  front_too_short,    // the back followed a front shown for less than front_min_s
  front_too_long,     // the front showing went on past front_max_s
  turn_too_long,      // no back tag within max_turn_s of the last front sighting
  back_too_short,     // the back showing ended before back_min_s
  back_too_long,      // the back showing went on past back_max_s
  wrong_order,        // the back shown first, or the front again before the back was long enough
  unknown_operator,   // a tag whose id is not a trained operator's
  operator_changed,   // another operator's back tag during the attempt
  person_in_the_way,  // someone else nearer than the operator, or next to them
  operator_lost,      // tags read but no person in front of the robot
};
inline constexpr std::size_t kTriggerRejectionCount = 12;
[[nodiscard]] const char* to_string(TriggerRejection reason) noexcept;

enum class TriggerEventKind : std::uint8_t { request, rejection };

struct TriggerEvent {
  TriggerEventKind kind = TriggerEventKind::request;
  TriggerRejection reason = TriggerRejection::too_near;  // for a rejection
  std::uint32_t operator_id = 0;
  hal::Nanos stamp_ns = 0;  // the capture time (or judged time) at which it was decided
};

// One control cycle's view.
struct TriggerInput {
  hal::Nanos now_ns = 0;
  const msg::TagFrame* frame = nullptr;  // the newest frame since the last cycle, or none
  bool armed = false;                    // a request can be taken now; otherwise all is ignored
  bool operator_present = false;         // the nearest person in front of the robot
  double operator_distance_m = 0.0;      // their distance from the laser
  double operator_speed_m_s = 0.0;       // as the people tracker has it
  std::uint8_t others_in_way = 0;        // other people nearer, or within reach of the operator
};

struct TriggerOutput {
  static constexpr std::size_t kMaxEvents = 8;
  mem::StaticVector<TriggerEvent, kMaxEvents> events;
  TriggerPhase phase = TriggerPhase::idle;
  std::uint32_t operator_id = 0;  // the attempt's operator (0: none)
};

class CollaborationTrigger {
 public:
  // Errors: an empty or inverted window, a gap or delay not positive, no operators.
  Status init(const TriggerConfig& config) noexcept;
  TriggerOutput update(const TriggerInput& input) noexcept;
  // Drops any attempt and watched showing (the counts stay).
  void reset() noexcept;

  [[nodiscard]] TriggerPhase phase() const noexcept { return phase_; }
  [[nodiscard]] std::uint32_t operator_id() const noexcept { return operator_; }
  [[nodiscard]] bool known(std::uint32_t operator_id) const noexcept;
  [[nodiscard]] std::uint32_t requests() const noexcept { return requests_; }
  [[nodiscard]] std::uint32_t rejections(TriggerRejection reason) const noexcept {
    return rejections_[static_cast<std::size_t>(reason)];
  }
  [[nodiscard]] std::uint32_t rejections_total() const noexcept;

 private:
  struct Watch {
    bool active = false;
    bool reported = false;
    std::uint32_t id = 0;
    msg::TagSide side = msg::TagSide::front;
    hal::Nanos first_ns = 0;
    hal::Nanos last_ns = 0;
  };
  enum class PersonCheck : std::uint8_t { ok, lost, in_the_way, too_near, too_far };

  void advance(hal::Nanos t_ns, TriggerOutput& out) noexcept;
  void apply(const msg::TagFrame& frame, hal::Nanos c_ns, TriggerOutput& out) noexcept;
  void on_front(hal::Nanos c_ns, TriggerOutput& out) noexcept;
  void on_back(hal::Nanos c_ns, TriggerOutput& out) noexcept;
  void idle_sighting(std::uint32_t id, msg::TagSide side, hal::Nanos c_ns, TriggerOutput& out) noexcept;
  void start_front(std::uint32_t id, hal::Nanos c_ns) noexcept;
  void start_back(hal::Nanos c_ns, TriggerOutput& out) noexcept;
  void reject(TriggerRejection reason, std::uint32_t id, hal::Nanos stamp_ns, TriggerOutput& out) noexcept;
  void count_rejection(TriggerRejection reason, std::uint32_t id, hal::Nanos stamp_ns, TriggerOutput& out) noexcept;
  void complete(hal::Nanos stamp_ns, TriggerOutput& out) noexcept;
  [[nodiscard]] PersonCheck check_person() const noexcept;

  TriggerConfig config_;
  hal::Nanos front_min_ns_ = 0, front_max_ns_ = 0, back_min_ns_ = 0, back_max_ns_ = 0;
  hal::Nanos turn_ns_ = 0, gap_ns_ = 0, delay_ns_ = 0;

  TriggerPhase phase_ = TriggerPhase::idle;
  std::uint32_t operator_ = 0;
  hal::Nanos first_front_ns_ = 0, last_front_ns_ = 0, first_back_ns_ = 0, last_back_ns_ = 0;
  bool front_standing_ = false;  // the front was seen with the operator standing, not only walking up
  hal::Nanos seen_ns_ = 0;                   // the attempt operator's latest sighting, either side
  msg::TagSide seen_side_ = msg::TagSide::front;
  Watch watch_;
  bool have_frame_ = false;
  hal::Nanos last_frame_ns_ = 0;
  TriggerInput person_;  // this cycle's view of the operator

  std::uint32_t requests_ = 0;
  std::array<std::uint32_t, kTriggerRejectionCount> rejections_{};
};

}  // namespace sen3bot::cobot
