#include "sen3bot/crowd/crowd.hpp"

#include <algorithm>
#include <cmath>
#include <span>

namespace sen3bot::crowd {
namespace {

using msg::norm;

// Step ends are k * step_s; a caller adding up its own ticks lands a few ulps short of them.
constexpr double kTimeSlack_s = 1e-9;

// The same limit as SocialForceModel::step(): more sub-steps per step is a mistaken parameter.
constexpr double kMaxSubsteps = 1e6;

bool finite(double x) noexcept { return std::isfinite(x); }
bool positive_finite(double x) noexcept { return x > 0.0 && finite(x); }
bool non_negative_finite(double x) noexcept { return x >= 0.0 && finite(x); }

Status check_person(const Person& p, std::size_t i) noexcept {
  if (!finite(p.start)) return Error::format(Errc::invalid_argument, "person %zu: start is not finite", i);
  if (p.goal_count > kMaxGoals) {
    return Error::format(Errc::capacity, "person %zu: %zu goals, at most %zu", i, p.goal_count, kMaxGoals);
  }
  for (std::size_t g = 0; g < p.goal_count; ++g) {
    if (!finite(p.goals[g])) return Error::format(Errc::invalid_argument, "person %zu: goal %zu is not finite", i, g);
  }
  if (!positive_finite(p.desired_speed_m_s)) {
    return Error::format(Errc::invalid_argument, "person %zu: desired speed %g m/s is not positive and finite", i,
                         p.desired_speed_m_s);
  }
  if (!positive_finite(p.radius_m)) {
    return Error::format(Errc::invalid_argument, "person %zu: radius %g m is not positive and finite", i, p.radius_m);
  }
  if (!finite(p.appear_s)) {
    return Error::format(Errc::invalid_argument, "person %zu: appear time %g s is not finite", i, p.appear_s);
  }
  if (p.loop && p.leave_at_goal) {
    return Error::format(Errc::invalid_argument, "person %zu: a looping route never ends: not with leave_at_goal", i);
  }
  // With no goal it would count as arrived and vanish the moment it appears.
  if (p.leave_at_goal && p.goal_count == 0) {
    return Error::format(Errc::invalid_argument, "person %zu: leaves at its goal but has no goal", i);
  }
  return Status::success();
}

Status check_recorded(const CrowdConfig& c) noexcept {
  if (!c.recording) return Error(Errc::invalid_argument, "a recorded crowd needs a recording");
  if (!finite(c.recording_offset)) return Error(Errc::invalid_argument, "recording offset is not finite");
  if (!finite(c.recording_start_s)) {
    return Error::format(Errc::invalid_argument, "recording start %g s is not finite", c.recording_start_s);
  }
  if (!positive_finite(c.radius_m)) {
    return Error::format(Errc::invalid_argument, "radius %g m of recorded people is not positive and finite",
                         c.radius_m);
  }
  // What Replay relies on; parse_recording() guarantees it, a hand-built recording may not.
  const std::vector<Track>& tracks = c.recording->tracks;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const std::vector<Sample>& samples = tracks[i].samples;
    const auto id = static_cast<long long>(tracks[i].person_id);
    if (samples.empty())
      return Error::format(Errc::invalid_argument, "recording track %zu (person %lld) is empty", i, id);
    for (std::size_t k = 0; k < samples.size(); ++k) {
      if (!finite(samples[k].time_s) || (k > 0 && !(samples[k].time_s > samples[k - 1].time_s))) {
        return Error::format(Errc::invalid_argument,
                             "recording track %zu (person %lld): sample %zu's time is not finite and increasing", i, id,
                             k);
      }
      if (!finite(samples[k].position + c.recording_offset)) {
        return Error::format(Errc::invalid_argument,
                             "recording track %zu (person %lld): sample %zu's position is not finite once offset", i,
                             id, k);
      }
    }
  }
  return Status::success();
}

Status check(const CrowdConfig& c) noexcept {
  const Behaviour b = c.behaviour;
  if (b != Behaviour::recorded && b != Behaviour::social && b != Behaviour::blind && b != Behaviour::orca) {
    return Error::format(Errc::invalid_argument, "unknown behaviour %d", static_cast<int>(b));
  }
  if (b == Behaviour::recorded) return check_recorded(c);

  if (!positive_finite(c.step_s)) {
    return Error::format(Errc::invalid_argument, "step %g s is not positive and finite", c.step_s);
  }
  // ORCA humans pass their goals with the social model's reach too.
  if (!non_negative_finite(c.social.goal_reach_m)) {
    return Error::format(Errc::invalid_argument, "goal reach %g m is not finite and non-negative",
                         c.social.goal_reach_m);
  }
  if (b == Behaviour::orca) {
    if (c.people.size() > kMaxOrcaAgents) {
      return Error::format(Errc::capacity, "%zu ORCA people, at most %zu", c.people.size(), kMaxOrcaAgents);
    }
    if (!positive_finite(c.orca.time_horizon_s)) {
      return Error::format(Errc::invalid_argument, "ORCA time horizon %g s is not positive and finite",
                           c.orca.time_horizon_s);
    }
    if (!(c.orca.neighbor_distance_m >= 0.0)) {
      return Error::format(Errc::invalid_argument, "ORCA neighbour distance %g m is negative",
                           c.orca.neighbor_distance_m);
    }
    if (!non_negative_finite(c.orca.radius_padding_m)) {
      return Error::format(Errc::invalid_argument, "ORCA radius padding %g m is not finite and non-negative",
                           c.orca.radius_padding_m);
    }
  } else {
    if (c.people.size() > kMaxWalkers) {
      return Error::format(Errc::capacity, "%zu walkers, at most %zu", c.people.size(), kMaxWalkers);
    }
    if (!positive_finite(c.social.relaxation_s)) {
      return Error::format(Errc::invalid_argument, "social relaxation time %g s is not positive and finite",
                           c.social.relaxation_s);
    }
    // Else SocialForceModel::step() would refuse every step and nobody would move.
    if (!positive_finite(c.social.max_substep_s) || !(c.step_s / c.social.max_substep_s <= kMaxSubsteps)) {
      return Error::format(Errc::invalid_argument, "step %g s in social sub-steps of %g s", c.step_s,
                           c.social.max_substep_s);
    }
    for (std::size_t i = 0; i < c.walls.size(); ++i) {
      if (!finite(c.walls[i].a) || !finite(c.walls[i].b)) {
        return Error::format(Errc::invalid_argument, "wall %zu: an end is not finite", i);
      }
    }
  }
  for (std::size_t i = 0; i < c.people.size(); ++i) {
    if (Status s = check_person(c.people[i], i); !s) return s;
  }
  return Status::success();
}

}  // namespace

const char* to_string(Behaviour behaviour) noexcept {
  switch (behaviour) {
    case Behaviour::recorded:
      return "recorded";
    case Behaviour::social:
      return "social";
    case Behaviour::blind:
      return "blind";
    case Behaviour::orca:
      return "orca";
  }
  return "unknown";
}

std::optional<Behaviour> parse_behaviour(std::string_view text) noexcept {
  for (const Behaviour b : {Behaviour::recorded, Behaviour::social, Behaviour::blind, Behaviour::orca}) {
    if (text == to_string(b)) return b;
  }
  return std::nullopt;
}

Result<std::unique_ptr<Crowd>> Crowd::create(const CrowdConfig& config) {
  if (Status s = check(config); !s) return s.error();
  return std::unique_ptr<Crowd>(new Crowd(config));
}

Crowd::Crowd(const CrowdConfig& config)
    : behaviour_(config.behaviour),
      step_s_(config.step_s),
      model_(config.social),
      orca_(config.orca),
      goal_reach_m_(config.social.goal_reach_m),
      offset_(config.recording_offset),
      recording_start_s_(config.recording_start_s),
      recorded_radius_m_(config.radius_m) {
  if (behaviour_ == Behaviour::recorded) {
    // Replay keeps its own copy: the shared recording may serve other runs meanwhile.
    replay_.emplace(*config.recording);
    states_.resize(replay_->track_count());
  } else {
    people_ = config.people;
    phases_.assign(people_.size(), Phase::waiting);
    states_.resize(people_.size());
    if (behaviour_ == Behaviour::orca) {
      agents_.resize(people_.size());
      next_goal_.assign(people_.size(), 0);
      for (std::size_t i = 0; i < people_.size(); ++i) {
        const Person& p = people_[i];
        agents_[i] = OrcaAgent{p.start, {}, {}, p.radius_m, p.desired_speed_m_s, false};
      }
    } else {
      walls_ = config.walls;
      walkers_.resize(people_.size());
      for (std::size_t i = 0; i < people_.size(); ++i) {
        const Person& p = people_[i];
        Walker& w = walkers_[i];
        w.position = p.start;
        w.radius_m = p.radius_m;
        w.desired_speed_m_s = p.desired_speed_m_s;
        // Cannot fail: create() checked goal_count <= kMaxGoals.
        static_cast<void>(set_route(w, std::span<const Point2D>(p.goals.data(), p.goal_count)));
        w.active = false;
        w.sees_robot = behaviour_ == Behaviour::social;
        w.group = p.group;
      }
    }
    enter_and_leave(0.0);
  }
  publish();
}

void Crowd::advance(double time_s, const RobotDisc* robot) noexcept {
  if (!finite(time_s) || time_s < time_s_) return;
  if (behaviour_ == Behaviour::recorded) {
    time_s_ = time_s;
    publish();
    return;
  }
  const std::uint64_t before = steps_;
  while (static_cast<double>(steps_ + 1) * step_s_ <= time_s + kTimeSlack_s) step(robot);
  if (steps_ == before) return;
  time_s_ = static_cast<double>(steps_) * step_s_;
  publish();
}

PersonState Crowd::state(std::size_t i) const noexcept { return i < states_.size() ? states_[i] : PersonState{}; }

void Crowd::step(const RobotDisc* robot) noexcept {
  if (behaviour_ == Behaviour::orca) {
    step_orca();
  } else {
    // Cannot fail: create() checked the walker count and the step against the sub-step.
    // Blind walkers have sees_robot false, so the robot passed here is nothing to them.
    static_cast<void>(model_.step(walkers_, walls_, robot, step_s_));
    for (std::size_t i = 0; i < walkers_.size(); ++i)
      if (people_[i].loop && reached_final_goal(walkers_[i])) walkers_[i].next_goal = 0;
  }
  ++steps_;
  enter_and_leave(static_cast<double>(steps_) * step_s_);
}

void Crowd::step_orca() noexcept {
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    OrcaAgent& a = agents_[i];
    if (!a.active) continue;
    const Person& p = people_[i];
    // After the last goal: stand on it (a person without goals stands at the start).
    Point2D target = p.start;
    if (next_goal_[i] < p.goal_count) {
      target = p.goals[next_goal_[i]];
    } else if (p.goal_count > 0) {
      target = p.goals[p.goal_count - 1];
    }
    const Point2D to_target = target - a.position;
    const double d = norm(to_target);
    // Full speed until within one step, then just the rest: it stops on the goal, not about it.
    const double speed = std::min(p.desired_speed_m_s, d / step_s_);
    a.preferred_velocity = d > 0.0 ? (speed / d) * to_target : Point2D{};
  }
  // Cannot fail: create() checked the count. No discs: ORCA humans never react to the robot.
  static_cast<void>(orca_step(agents_, {}, orca_, step_s_));
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    if (!agents_[i].active) continue;
    const Person& p = people_[i];
    std::size_t& next = next_goal_[i];
    while (next < p.goal_count && norm(p.goals[next] - agents_[i].position) < goal_reach_m_) ++next;
    if (p.loop && next >= p.goal_count) next = 0;
  }
}

void Crowd::enter_and_leave(double t) noexcept {
  const bool orca = behaviour_ == Behaviour::orca;
  for (std::size_t i = 0; i < people_.size(); ++i) {
    const Person& p = people_[i];
    if (phases_[i] == Phase::present && p.leave_at_goal) {
      const bool arrived = orca ? next_goal_[i] >= p.goal_count : reached_final_goal(walkers_[i]);
      if (arrived) {
        phases_[i] = Phase::gone;
        (orca ? agents_[i].active : walkers_[i].active) = false;
      }
    } else if (phases_[i] == Phase::waiting && p.appear_s <= t + kTimeSlack_s) {
      phases_[i] = Phase::present;
      (orca ? agents_[i].active : walkers_[i].active) = true;
    }
  }
}

void Crowd::publish() noexcept {
  if (behaviour_ == Behaviour::recorded) {
    const double at_s = recording_start_s_ + time_s_;
    for (std::size_t i = 0; i < states_.size(); ++i) {
      const WalkerState w = replay_->state_at(i, at_s);
      states_[i] = w.visible ? PersonState{w.position + offset_, w.velocity_m_s, recorded_radius_m_, true}
                             : PersonState{{}, {}, recorded_radius_m_, false};
    }
    return;
  }
  const bool orca = behaviour_ == Behaviour::orca;
  for (std::size_t i = 0; i < states_.size(); ++i) {
    const double radius_m = people_[i].radius_m;
    if (phases_[i] != Phase::present) {
      states_[i] = PersonState{{}, {}, radius_m, false};
    } else if (orca) {
      states_[i] = PersonState{agents_[i].position, agents_[i].velocity, radius_m, true};
    } else {
      states_[i] = PersonState{walkers_[i].position, walkers_[i].velocity, radius_m, true};
    }
  }
}

}  // namespace sen3bot::crowd
