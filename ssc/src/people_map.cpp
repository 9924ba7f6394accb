#include "sen3bot/ssc/people_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "sen3bot/ssc/site.hpp"

namespace sen3bot::ssc {
namespace {

RobotMask robot_bit(RobotId robot) noexcept { return robot < kMaxRobots ? (RobotMask{1} << robot) : 0; }

Point predict(const Track& t, Nanos at) noexcept {
  const double dt = std::max(0.0, hal::to_seconds(at - t.last_seen));
  return {t.position.x_m + t.vx * dt, t.position.y_m + t.vy * dt};
}

}  // namespace

PeopleMap::PeopleMap(const PeopleMapConfig& config) noexcept : config_(config) {
  config_.max_tracks = std::min(config_.max_tracks, kMaxTracks);
}

void PeopleMap::update(const PeopleReport& report) noexcept {
  const RobotMask bit = robot_bit(report.robot);
  // This robot's earlier sighting is replaced by the new one.
  for (Track& t : tracks_) t.seen_by &= ~bit;

  // Every (observation, track) pair inside the gate, nearest first, assigned one to one.
  struct Pair {
    double d;
    std::uint8_t obs;
    std::uint8_t track;
  };
  static_assert(kMaxPeoplePerReport <= 255 && kMaxTracks <= 255);
  StaticVector<Pair, kMaxPeoplePerReport * 8> pairs;  // per observation, its 8 nearest tracks
  for (std::size_t o = 0; o < report.people.size(); ++o) {
    const Point p{report.people[o].x, report.people[o].y};
    std::array<Pair, 8> best{};
    std::size_t n = 0;
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const double d = distance(p, predict(tracks_[k], report.stamp));
      if (d > config_.gate) continue;
      const Pair pair{d, static_cast<std::uint8_t>(o), static_cast<std::uint8_t>(k)};
      if (n < best.size()) {
        best[n++] = pair;
      } else {
        auto worst = std::max_element(best.begin(), best.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
        if (pair.d < worst->d) *worst = pair;
      }
    }
    for (std::size_t i = 0; i < n; ++i) (void)pairs.push_back(best[i]);
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });

  std::array<int, kMaxPeoplePerReport> match;
  match.fill(-1);
  std::array<bool, kMaxTracks> taken{};
  for (const Pair& pair : pairs) {
    if (match[pair.obs] >= 0 || taken[pair.track]) continue;
    match[pair.obs] = pair.track;
    taken[pair.track] = true;
  }

  const double g = std::clamp(config_.position_gain, 0.0, 1.0);
  for (std::size_t o = 0; o < report.people.size(); ++o) {
    const PersonObservation& obs = report.people[o];
    if (match[o] >= 0) {
      Track& t = tracks_[static_cast<std::size_t>(match[o])];
      const Point pred = predict(t, report.stamp);
      t.position = {g * obs.x + (1 - g) * pred.x_m, g * obs.y + (1 - g) * pred.y_m};
      t.vx = g * obs.vx + (1 - g) * t.vx;
      t.vy = g * obs.vy + (1 - g) * t.vy;
      t.last_seen = std::max(t.last_seen, report.stamp);
      t.seen_by |= bit;
      ++t.updates;
      if (distance(t.position, t.first_position) > config_.dynamic_distance) t.dynamic = true;
      continue;
    }
    if (tracks_.size() >= config_.max_tracks) {
      ++overflow_;
      continue;
    }
    Track t;
    t.id = next_id_++;
    t.position = t.first_position = {obs.x, obs.y};
    t.vx = obs.vx;
    t.vy = obs.vy;
    t.first_seen = t.last_seen = report.stamp;
    t.seen_by = bit;
    t.updates = 1;
    (void)tracks_.push_back(t);  // room checked above
  }
  merge_duplicates();
}

// A person first seen by two robots apart from each other (beyond the gate, before one report
// could join the other's track) would otherwise stay two tracks when the estimates converge.
// Two tracks no robot sees together merge when closer than merge_distance; a track no robot
// sees any more (every robot that saw it now reports without it) merges into a seen one
// within the gate: the robots have moved that person over to it.
void PeopleMap::merge_duplicates() noexcept {
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    for (std::size_t j = i + 1; j < tracks_.size();) {
      Track& a = tracks_[i];
      const Track& b = tracks_[j];
      const bool orphan = (a.seen_by == 0) != (b.seen_by == 0);
      const double reach = orphan ? config_.gate : config_.merge_distance;
      if ((a.seen_by & b.seen_by) == 0 && distance(a.position, b.position) <= reach) {
        // Keep the older track's id and first position, so the dynamic test keeps its origin.
        const bool b_older = b.first_seen < a.first_seen;
        if (b_older) {
          a.id = b.id;
          a.first_position = b.first_position;
          a.first_seen = b.first_seen;
        }
        if (b.last_seen > a.last_seen) {
          a.position = b.position;
          a.vx = b.vx;
          a.vy = b.vy;
          a.last_seen = b.last_seen;
        }
        a.dynamic = a.dynamic || b.dynamic || distance(a.position, a.first_position) > config_.dynamic_distance;
        a.seen_by |= b.seen_by;
        a.updates += b.updates;
        tracks_.erase(tracks_.begin() + j);
      } else {
        ++j;
      }
    }
  }
}

void PeopleMap::expire(Nanos now) noexcept {
  tracks_.remove_if([&](const Track& t) { return now - t.last_seen > config_.timeout; });
}

AreaPeople PeopleMap::in_area(std::span<const Point> polygon) const noexcept {
  AreaPeople out;
  for (const Track& t : tracks_) {
    if (!contains(polygon, t.position)) continue;
    ++out.count;
    if (t.dynamic) ++out.dynamic;
  }
  return out;
}

}  // namespace sen3bot::ssc
