#include "sen3bot/cobot/trigger.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::cobot {

const char* to_string(TriggerPhase phase) noexcept {
  switch (phase) {
    case TriggerPhase::idle: return "idle";
    case TriggerPhase::front: return "front";
    case TriggerPhase::turning: return "turning";
    case TriggerPhase::back: return "back";
    case TriggerPhase::cooldown: return "cooldown";
  }
  return "unknown";
}

const char* to_string(TriggerRejection reason) noexcept {
  switch (reason) {
    case TriggerRejection::too_near: return "too_near";
    case TriggerRejection::too_far: return "too_far";
    case TriggerRejection::front_too_short: return "front_too_short";
    case TriggerRejection::front_too_long: return "front_too_long";
    case TriggerRejection::turn_too_long: return "turn_too_long";
    case TriggerRejection::back_too_short: return "back_too_short";
    case TriggerRejection::back_too_long: return "back_too_long";
    case TriggerRejection::wrong_order: return "wrong_order";
    case TriggerRejection::unknown_operator: return "unknown_operator";
    case TriggerRejection::operator_changed: return "operator_changed";
    case TriggerRejection::person_in_the_way: return "person_in_the_way";
    case TriggerRejection::operator_lost: return "operator_lost";
  }
  return "unknown";
}

Status CollaborationTrigger::init(const TriggerConfig& config) noexcept {
  if (!(config.min_distance_m >= 0.0 && config.min_distance_m <= config.max_distance_m) ||
      !(config.front_min_s > 0.0 && config.front_min_s <= config.front_max_s) ||
      !(config.back_min_s > 0.0 && config.back_min_s <= config.back_max_s) || !(config.max_turn_s > 0.0) ||
      !(config.max_sighting_gap_s > 0.0) || !(config.max_frame_delay_s >= 0.0) || config.operators.empty()) {
    return Error::format(Errc::config, "cobot trigger: 0 <= min_distance_m <= max_distance_m, 0 < front_min_s <= "
                                       "front_max_s, 0 < back_min_s <= back_max_s, max_turn_s > 0, "
                                       "max_sighting_gap_s > 0, max_frame_delay_s >= 0 and at least one operator");
  }
  for (std::uint32_t id : config.operators) {
    if (id == 0) return Error(Errc::config, "cobot trigger: operator id 0 is reserved for none");
  }
  config_ = config;
  front_min_ns_ = hal::from_seconds(config.front_min_s);
  front_max_ns_ = hal::from_seconds(config.front_max_s);
  back_min_ns_ = hal::from_seconds(config.back_min_s);
  back_max_ns_ = hal::from_seconds(config.back_max_s);
  turn_ns_ = hal::from_seconds(config.max_turn_s);
  gap_ns_ = hal::from_seconds(config.max_sighting_gap_s);
  delay_ns_ = hal::from_seconds(config.max_frame_delay_s);
  reset();
  requests_ = 0;
  rejections_ = {};
  return Status::success();
}

void CollaborationTrigger::reset() noexcept {
  phase_ = TriggerPhase::idle;
  operator_ = 0;
  first_front_ns_ = last_front_ns_ = first_back_ns_ = last_back_ns_ = seen_ns_ = 0;
  watch_ = Watch{};
  have_frame_ = false;
}

bool CollaborationTrigger::known(std::uint32_t operator_id) const noexcept {
  return operator_id != 0 &&
         std::find(config_.operators.begin(), config_.operators.end(), operator_id) != config_.operators.end();
}

std::uint32_t CollaborationTrigger::rejections_total() const noexcept {
  std::uint32_t total = 0;
  for (std::uint32_t n : rejections_) total += n;
  return total;
}

TriggerOutput CollaborationTrigger::update(const TriggerInput& input) noexcept {
  TriggerOutput out;
  if (!input.armed) {
    // Not taking requests: whatever is shown now is not an attempt, and one under way is dropped.
    reset();
  } else {
    person_ = input;
    const msg::TagFrame* frame = input.frame;
    // A frame taken no later than the last one is a repeat: it adds nothing.
    if (frame != nullptr && (!have_frame_ || frame->capture_ns > last_frame_ns_)) {
      advance(frame->capture_ns, out);
      apply(*frame, frame->capture_ns, out);
    }
    advance(input.now_ns - delay_ns_, out);
  }
  if (input.frame != nullptr && (!have_frame_ || input.frame->capture_ns > last_frame_ns_)) {
    have_frame_ = true;
    last_frame_ns_ = input.frame->capture_ns;
  }
  out.phase = phase_;
  out.operator_id = phase_ == TriggerPhase::idle ? 0 : operator_;
  return out;
}

// Ends what time t has ended: a showing with no sighting for longer than the gap, a turn
// longer than allowed. Loops because one ending may start another phase that t also ends.
void CollaborationTrigger::advance(hal::Nanos t_ns, TriggerOutput& out) noexcept {
  for (;;) {
    const TriggerPhase before = phase_;
    switch (phase_) {
      case TriggerPhase::idle: break;
      case TriggerPhase::front:
        // Whether the front was long enough is judged when the back comes: a short front that
        // no back follows was a glimpse (someone walking past), not an attempt.
        if (t_ns - last_front_ns_ > gap_ns_) phase_ = TriggerPhase::turning;
        break;
      case TriggerPhase::turning:
        if (t_ns - last_front_ns_ > turn_ns_) {
          if (last_front_ns_ - first_front_ns_ < front_min_ns_) {
            phase_ = TriggerPhase::idle;
            operator_ = 0;
          } else {
            reject(TriggerRejection::turn_too_long, operator_, t_ns, out);
          }
        }
        break;
      case TriggerPhase::back:
        if (t_ns - last_back_ns_ > gap_ns_) {
          if (last_back_ns_ - first_back_ns_ < back_min_ns_) {
            reject(TriggerRejection::back_too_short, operator_, t_ns, out);
          } else {
            complete(t_ns, out);
          }
        }
        break;
      case TriggerPhase::cooldown:
        // After a front, the back may still come a turn later and belongs to the same attempt.
        if (t_ns - seen_ns_ > (seen_side_ == msg::TagSide::front ? std::max(turn_ns_, gap_ns_) : gap_ns_)) {
          phase_ = TriggerPhase::idle;
          operator_ = 0;
        }
        break;
    }
    if (phase_ == before) break;
  }
  if (watch_.active &&
      t_ns - watch_.last_ns > (watch_.side == msg::TagSide::front ? std::max(turn_ns_, gap_ns_) : gap_ns_))
    watch_ = Watch{};
}

void CollaborationTrigger::apply(const msg::TagFrame& frame, hal::Nanos c_ns, TriggerOutput& out) noexcept {
  const std::size_t count = std::min<std::size_t>(frame.count, msg::TagFrame::kMax);
  if (phase_ == TriggerPhase::front || phase_ == TriggerPhase::turning || phase_ == TriggerPhase::back) {
    bool front = false;
    bool back = false;
    std::uint32_t other_back = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const msg::TagSighting& tag = frame.tags[i];
      if (tag.operator_id == operator_) {
        (tag.side == msg::TagSide::front ? front : back) = true;
      } else if (tag.side == msg::TagSide::back && known(tag.operator_id) && other_back == 0) {
        other_back = tag.operator_id;
      }
    }
    if (other_back != 0) {
      reject(TriggerRejection::operator_changed, operator_, c_ns, out);
    } else if (front != back) {
      // Both sides in one frame (the leg seen edge-on) tell nothing about the phase.
      seen_ns_ = c_ns;
      seen_side_ = front ? msg::TagSide::front : msg::TagSide::back;
      if (front) {
        on_front(c_ns, out);
      } else {
        on_back(c_ns, out);
      }
    }
  }
  if (phase_ == TriggerPhase::cooldown) {
    // The ended attempt's operator, still showing or turning: ignored. Facing the robot again
    // after the back, or after the tags were hidden for longer than a gap, starts a new attempt
    // (the operator who has just toggled may toggle back).
    for (std::size_t i = 0; i < count; ++i) {
      const msg::TagSighting& tag = frame.tags[i];
      if (tag.operator_id != operator_) continue;
      if (tag.side == msg::TagSide::front && (seen_side_ == msg::TagSide::back || c_ns - seen_ns_ > gap_ns_)) {
        phase_ = TriggerPhase::idle;
        operator_ = 0;
        break;
      }
      seen_ns_ = std::max(seen_ns_, c_ns);
      seen_side_ = tag.side;
    }
  }
  if (phase_ == TriggerPhase::idle) {
    for (std::size_t i = 0; i < count && phase_ == TriggerPhase::idle; ++i) {
      const msg::TagSighting& tag = frame.tags[i];
      bool repeat = false;
      for (std::size_t j = 0; j < i; ++j)
        repeat = repeat || (frame.tags[j].operator_id == tag.operator_id && frame.tags[j].side == tag.side);
      if (!repeat) idle_sighting(tag.operator_id, tag.side, c_ns, out);
    }
  }
}

void CollaborationTrigger::on_front(hal::Nanos c_ns, TriggerOutput& out) noexcept {
  switch (phase_) {
    case TriggerPhase::front: {
      const PersonCheck check = check_person();
      last_front_ns_ = c_ns;
      if (person_.operator_speed_m_s > config_.standing_speed_m_s) first_front_ns_ = c_ns;  // still walking up
      else front_standing_ = true;
      if (check == PersonCheck::lost) reject(TriggerRejection::operator_lost, operator_, c_ns, out);
      else if (check == PersonCheck::in_the_way) reject(TriggerRejection::person_in_the_way, operator_, c_ns, out);
      else if (check == PersonCheck::too_near) reject(TriggerRejection::too_near, operator_, c_ns, out);
      else if (check == PersonCheck::too_far) reject(TriggerRejection::too_far, operator_, c_ns, out);
      else if (last_front_ns_ - first_front_ns_ > front_max_ns_)
        reject(TriggerRejection::front_too_long, operator_, c_ns, out);
      break;
    }
    case TriggerPhase::turning: {
      // Faced the robot again without showing the back: the operator starts over. The front
      // showing already done was long enough, so nothing is refused.
      const std::uint32_t id = operator_;
      phase_ = TriggerPhase::idle;
      operator_ = 0;
      idle_sighting(id, msg::TagSide::front, c_ns, out);
      break;
    }
    case TriggerPhase::back:
      if (last_back_ns_ - first_back_ns_ >= back_min_ns_) {
        // The back showing was long enough and ends here with the turn to the front.
        complete(c_ns, out);
        phase_ = TriggerPhase::idle;
        operator_ = 0;
      } else {
        reject(TriggerRejection::wrong_order, operator_, c_ns, out);
      }
      break;
    case TriggerPhase::idle:
    case TriggerPhase::cooldown: break;
  }
}

void CollaborationTrigger::on_back(hal::Nanos c_ns, TriggerOutput& out) noexcept {
  if ((phase_ == TriggerPhase::front || phase_ == TriggerPhase::turning) && !front_standing_) {
    // The front was only seen while they walked up: the back is where their showing starts.
    const std::uint32_t id = operator_;
    phase_ = TriggerPhase::idle;
    operator_ = 0;
    idle_sighting(id, msg::TagSide::back, c_ns, out);
    return;
  }
  switch (phase_) {
    case TriggerPhase::front:
      if (last_front_ns_ - first_front_ns_ < front_min_ns_) {
        reject(TriggerRejection::front_too_short, operator_, c_ns, out);
        break;
      }
      start_back(c_ns, out);
      break;
    case TriggerPhase::turning:
      if (last_front_ns_ - first_front_ns_ < front_min_ns_) {
        reject(TriggerRejection::front_too_short, operator_, c_ns, out);
        break;
      }
      start_back(c_ns, out);
      break;
    case TriggerPhase::back: {
      const PersonCheck check = check_person();
      const bool walking_off = person_.operator_speed_m_s > config_.standing_speed_m_s;
      if ((check != PersonCheck::ok || walking_off) && last_back_ns_ - first_back_ns_ >= back_min_ns_) {
        // Walking off (or out of the window) with the back still towards the robot after
        // showing it long enough: the showing ended where they set off.
        complete(last_back_ns_, out);
        break;
      }
      last_back_ns_ = c_ns;
      if (check == PersonCheck::lost) reject(TriggerRejection::operator_lost, operator_, c_ns, out);
      else if (check == PersonCheck::in_the_way) reject(TriggerRejection::person_in_the_way, operator_, c_ns, out);
      else if (check == PersonCheck::too_near) reject(TriggerRejection::too_near, operator_, c_ns, out);
      else if (check == PersonCheck::too_far) reject(TriggerRejection::too_far, operator_, c_ns, out);
      else if (last_back_ns_ - first_back_ns_ > back_max_ns_)
        reject(TriggerRejection::back_too_long, operator_, c_ns, out);
      break;
    }
    case TriggerPhase::idle:
    case TriggerPhase::cooldown: break;
  }
}

void CollaborationTrigger::start_back(hal::Nanos c_ns, TriggerOutput& out) noexcept {
  if (c_ns - last_front_ns_ > turn_ns_) {
    reject(TriggerRejection::turn_too_long, operator_, c_ns, out);
    return;
  }
  switch (check_person()) {
    case PersonCheck::ok:
      phase_ = TriggerPhase::back;
      first_back_ns_ = last_back_ns_ = c_ns;
      break;
    case PersonCheck::lost: reject(TriggerRejection::operator_lost, operator_, c_ns, out); break;
    case PersonCheck::in_the_way: reject(TriggerRejection::person_in_the_way, operator_, c_ns, out); break;
    case PersonCheck::too_near: reject(TriggerRejection::too_near, operator_, c_ns, out); break;
    case PersonCheck::too_far: reject(TriggerRejection::too_far, operator_, c_ns, out); break;
  }
}

void CollaborationTrigger::start_front(std::uint32_t id, hal::Nanos c_ns) noexcept {
  phase_ = TriggerPhase::front;
  front_standing_ = person_.operator_speed_m_s <= config_.standing_speed_m_s;
  operator_ = id;
  first_front_ns_ = last_front_ns_ = seen_ns_ = c_ns;
  first_back_ns_ = last_back_ns_ = 0;
  seen_side_ = msg::TagSide::front;
  watch_ = Watch{};
}

// A sighting while no attempt is under way. A trained operator's front tag with the operator
// in place starts one; anything else is watched as one showing, and a showing that lasts
// front_min_s is taken for an attempt and refused once.
void CollaborationTrigger::idle_sighting(std::uint32_t id, msg::TagSide side, hal::Nanos c_ns,
                                         TriggerOutput& out) noexcept {
  const PersonCheck check = check_person();
  // A refused showing going on (the back shown first, now the front) is the same attempt.
  const bool refused_showing = watch_.active && watch_.id == id && watch_.reported;
  if (side == msg::TagSide::front && known(id) && check == PersonCheck::ok && !refused_showing) {
    start_front(id, c_ns);
    return;
  }
  // One showing watched at a time: one id's tags, either side (a refused front and the back
  // after the turn are one attempt, refused once).
  const bool same = watch_.active && watch_.id == id;
  if (watch_.active && !same) return;
  if (!same) watch_ = Watch{true, false, id, side, c_ns, c_ns};
  if (watch_.side != side) {
    watch_.side = side;
    watch_.first_ns = c_ns;  // each side is timed on its own
  }
  watch_.last_ns = c_ns;
  if (watch_.reported || watch_.last_ns - watch_.first_ns < front_min_ns_) return;
  if (!known(id)) {
    count_rejection(TriggerRejection::unknown_operator, id, c_ns, out);
  } else if (side == msg::TagSide::back) {
    // Only an operator standing in place with the back turned: one walking away is no attempt.
    if (check != PersonCheck::ok) return;
    count_rejection(TriggerRejection::wrong_order, id, c_ns, out);
  } else if (check == PersonCheck::lost) {
    count_rejection(TriggerRejection::operator_lost, id, c_ns, out);
  } else if (check == PersonCheck::in_the_way) {
    count_rejection(TriggerRejection::person_in_the_way, id, c_ns, out);
  } else if (check == PersonCheck::too_near) {
    count_rejection(TriggerRejection::too_near, id, c_ns, out);
  } else {
    count_rejection(TriggerRejection::too_far, id, c_ns, out);
  }
  watch_.reported = true;
}

void CollaborationTrigger::count_rejection(TriggerRejection reason, std::uint32_t id, hal::Nanos stamp_ns,
                                           TriggerOutput& out) noexcept {
  ++rejections_[static_cast<std::size_t>(reason)];
  TriggerEvent event;
  event.kind = TriggerEventKind::rejection;
  event.reason = reason;
  event.operator_id = id;
  event.stamp_ns = stamp_ns;
  (void)out.events.push_back(event);  // a full list drops the event; the count keeps it
}

void CollaborationTrigger::reject(TriggerRejection reason, std::uint32_t id, hal::Nanos stamp_ns,
                                  TriggerOutput& out) noexcept {
  count_rejection(reason, id, stamp_ns, out);
  // The rest of the refused showing is no new attempt: the cooldown lasts at least a gap.
  phase_ = TriggerPhase::cooldown;
  seen_ns_ = std::max(seen_ns_, stamp_ns);
}

void CollaborationTrigger::complete(hal::Nanos stamp_ns, TriggerOutput& out) noexcept {
  ++requests_;
  TriggerEvent event;
  event.kind = TriggerEventKind::request;
  event.operator_id = operator_;
  event.stamp_ns = stamp_ns;
  (void)out.events.push_back(event);
  phase_ = TriggerPhase::cooldown;
  seen_side_ = msg::TagSide::back;
  seen_ns_ = std::max(seen_ns_, stamp_ns);
}

CollaborationTrigger::PersonCheck CollaborationTrigger::check_person() const noexcept {
  if (!person_.operator_present) return PersonCheck::lost;
  if (person_.others_in_way > 0) return PersonCheck::in_the_way;
  if (person_.operator_distance_m < config_.min_distance_m) return PersonCheck::too_near;
  if (person_.operator_distance_m > config_.max_distance_m) return PersonCheck::too_far;
  return PersonCheck::ok;
}

}  // namespace sen3bot::cobot
