#include "sen3bot/crowd/walk_stats.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "sen3bot/crowd/random.hpp"
#include "sen3bot/crowd/scene.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {
namespace {

using msg::cross;
using msg::norm;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Recorded times are frame counts times 0.04 s: a period apart up to rounding, never a
// fraction of one. Anything within this share of the period is "one period".
constexpr double kPeriodTolerance = 1e-3;

// The benchmark's walkers (scene.hpp): same draws, same bounds.
constexpr double kMinWalkM = 2.0;
constexpr double kSpacingM = 0.2;  // CrowdNav's discomfort distance, as the scenes space walkers
constexpr int kMaxDraws = 1000;
constexpr double kRouteJitterM = 0.2;

// A sample's place among the walks.
struct Entry {
  std::int64_t moment = 0;  // time / period, rounded
  std::size_t track = 0;
  std::size_t index = 0;
};


// matched_crowd's floor: the recording's extent with walls on its border, starts and goals
// kWallGapM inside them.
struct Floor {
  Point2D lo, hi;

  [[nodiscard]] std::vector<Wall> walls() const {
    return {{lo, {hi.x_m, lo.y_m}}, {{hi.x_m, lo.y_m}, hi}, {hi, {lo.x_m, hi.y_m}}, {{lo.x_m, hi.y_m}, lo}};
  }
  // Side 0 bottom, 1 right, 2 top, 3 left; u in [0, 1) along it, 0.5 m inside the walls.
  [[nodiscard]] Point2D on_side(int side, double u) const {
    const Point2D a = lo + Point2D{kWallGapM, kWallGapM};
    const Point2D b = hi - Point2D{kWallGapM, kWallGapM};
    const Point2D p = a + Point2D{u * (b.x_m - a.x_m), u * (b.y_m - a.y_m)};
    switch (side) {
      case 0:
        return {p.x_m, a.y_m};
      case 1:
        return {b.x_m, p.y_m};
      case 2:
        return {p.x_m, b.y_m};
      default:
        return {a.x_m, p.y_m};
    }
  }
  [[nodiscard]] Point2D clamp_inside(Point2D q) const {
    return Point2D{std::clamp(q.x_m, lo.x_m + kWallGapM, hi.x_m - kWallGapM),
                   std::clamp(q.y_m, lo.y_m + kWallGapM, hi.y_m - kWallGapM)};
  }
  [[nodiscard]] bool inside(Point2D q) const {
    return q.x_m >= lo.x_m + kWallGapM && q.x_m <= hi.x_m - kWallGapM && q.y_m >= lo.y_m + kWallGapM &&
           q.y_m <= hi.y_m - kWallGapM;
  }
};

using Route = std::array<Point2D, 2>;

// Where a walker nominally is at time t (straight, at its desired speed), if there.
std::optional<Point2D> nominal(const Person& q, double end_s, double t) {
  if (t < q.appear_s || t > end_s) return std::nullopt;
  const Point2D walk = q.goals[0] - q.start;
  const double length = norm(walk);
  const double along = std::min(length, (t - q.appear_s) * q.desired_speed_m_s);
  return length > 0.0 ? q.start + (along / length) * walk : q.start;
}

// The options matched_crowd cannot build from.
Status check_matched(const Recording& recording, const Summary& summary, const MatchedCrowdOptions& options) {
  if (summary.samples == 0) {
    return Error::format(Errc::invalid_argument, "matched_crowd: %s has no samples", recording.name.c_str());
  }
  const Extent area = summary.extent;
  const double width = area.max.x_m - area.min.x_m;
  const double height = area.max.y_m - area.min.y_m;
  // Room for starts and goals 0.5 m inside the walls, and a walk of 2 m between them.
  if (!(width > 2.0 * kWallGapM + kMinWalkM && height > 2.0 * kWallGapM + kMinWalkM)) {
    return Error::format(Errc::invalid_argument, "matched_crowd: %s spans only %g x %g m", recording.name.c_str(),
                         width, height);
  }
  if (!(options.duration_s > 0.0 && std::isfinite(options.duration_s))) {
    return Error::format(Errc::invalid_argument, "matched_crowd: duration %g s is not positive and finite",
                         options.duration_s);
  }
  if (!(options.pair_share >= 0.0 && options.pair_share <= 1.0)) {
    return Error::format(Errc::invalid_argument, "matched_crowd: pair share %g is not in [0, 1]", options.pair_share);
  }
  return Status::success();
}

// The recorded routes long enough to walk: from each track's first place to its last.
Result<std::vector<Route>> recorded_routes(const Recording& recording) {
  std::vector<Route> routes;
  for (const Track& track : recording.tracks) {
    const Point2D a = track.samples.front().position, b = track.samples.back().position;
    if (norm(b - a) >= kMinWalkM) routes.push_back({a, b});
  }
  if (routes.empty()) {
    return Error::format(Errc::invalid_argument, "matched_crowd: %s has no track of %g m or more to walk",
                         recording.name.c_str(), kMinWalkM);
  }
  return routes;
}

// matched_crowd's walkers, slot by slot: the slot due first gets its next walker, clear of
// everyone nominally present at that moment (a companion also of its walker), who appears when
// the last would nominally arrive.
class WalkerPlan {
 public:
  WalkerPlan(CrowdConfig& config, const Floor& floor, const std::vector<Route>& routes, std::uint64_t seed)
      : config_(config), floor_(floor), routes_(routes), rng_(seed) {}

  Status run(std::size_t slots, double pair_chance, double duration_s) {
    const double relaxation_s = config_.social.relaxation_s;
    const double reach_m = config_.social.goal_reach_m;
    std::uint32_t groups = 0;
    std::vector<double> slot_next_s(slots, 0.0);  // when each slot's next walker appears
    std::vector<bool> slot_first(slots, true);     // the slot's first walk starts part-way
    for (;;) {
      // The slot due first, so everyone nominally present at that moment is already placed.
      const auto due = std::min_element(slot_next_s.begin(), slot_next_s.end());
      const double t = *due;
      if (t >= duration_s) return Status::success();
      const bool first = slot_first[static_cast<std::size_t>(due - slot_next_s.begin())];
      slot_first[static_cast<std::size_t>(due - slot_next_s.begin())] = false;
      Person p;
      p.radius_m = kWalkerRadiusM;
      p.desired_speed_m_s = draw_walker_speed(rng_);  // first, so spacing does not bias it
      p.goal_count = 1;
      p.leave_at_goal = true;
      p.appear_s = t;
      const bool pair = pair_chance > 0.0 && unit_uniform(rng_) < pair_chance;
      Person companion = p;
      if (!place(p, companion, pair, first, t)) {
        return Error::format(Errc::capacity, "matched_crowd: no room for walker %zu at %g s in %d draws",
                             config_.people.size(), t, kMaxDraws);
      }
      if (config_.people.size() + (pair ? 2 : 1) > kMaxWalkers) {
        return Error::format(Errc::capacity, "matched_crowd: %zu at once for %g s needs more than %zu walkers", slots,
                             duration_s, kMaxWalkers);
      }
      // From rest a walker lags its desired speed by the relaxation time; it leaves within reach.
      const double walk_s = std::max(0.0, norm(p.goals[0] - p.start) - reach_m) / p.desired_speed_m_s + relaxation_s;
      if (pair) {
        p.group = companion.group = ++groups;
        end_s_.push_back(t + walk_s);
        config_.people.push_back(companion);
      }
      end_s_.push_back(t + walk_s);
      config_.people.push_back(p);
      *due = t + walk_s;
    }
  }

 private:
  // Clear of everyone nominally present at time t.
  [[nodiscard]] bool room_for(const Person& who, double t) const {
    for (std::size_t j = 0; j < config_.people.size(); ++j) {
      const std::optional<Point2D> q = nominal(config_.people[j], end_s_[j], t);
      if (q && norm(*q - who.start) < who.radius_m + config_.people[j].radius_m + kSpacingM) return false;
    }
    return true;
  }

  // A walk's ends: a recorded route with jitter, or points on two different sides.
  void draw_ends(Point2D& a, Point2D& b) {
    if (!routes_.empty()) {
      const auto pick = static_cast<std::size_t>(unit_uniform(rng_) * static_cast<double>(routes_.size()));
      const Route& route = routes_[std::min(routes_.size() - 1, pick)];
      a = floor_.clamp_inside(route[0] + Point2D{kRouteJitterM * standard_normal(rng_), kRouteJitterM * standard_normal(rng_)});
      b = floor_.clamp_inside(route[1] + Point2D{kRouteJitterM * standard_normal(rng_), kRouteJitterM * standard_normal(rng_)});
    } else {
      const int from = std::min(3, static_cast<int>(unit_uniform(rng_) * 4.0));
      const int to = (from + 1 + std::min(2, static_cast<int>(unit_uniform(rng_) * 3.0))) % 4;
      a = floor_.on_side(from, unit_uniform(rng_));
      b = floor_.on_side(to, unit_uniform(rng_));
    }
  }

  // Draws p's walk (a slot's first starts part-way along it) and, for a pair, its companion's
  // beside it, until they have room; false after kMaxDraws draws.
  bool place(Person& p, Person& companion, bool pair, bool first, double t) {
    bool placed = false;
    for (int attempt = 0; attempt < kMaxDraws && !placed; ++attempt) {
      Point2D a, b;
      draw_ends(a, b);
      const double along = first ? unit_uniform(rng_) : 0.0;
      if (norm(b - a) < kMinWalkM) continue;
      p.start = a + along * (b - a);
      p.goals[0] = b;
      placed = room_for(p, t);
      if (placed && pair) {
        // Beside the walker, on its left if there is room, else on its right.
        const Point2D left = (kCompanionGapM / norm(b - a)) * perpendicular(b - a);
        companion.start = p.start + left;
        companion.goals[0] = b + left;
        if (!floor_.inside(companion.start) || !floor_.inside(companion.goals[0])) {
          companion.start = p.start - left;
          companion.goals[0] = b - left;
        }
        placed = floor_.inside(companion.start) && floor_.inside(companion.goals[0]) && room_for(companion, t);
      }
    }
    return placed;
  }

  CrowdConfig& config_;
  const Floor& floor_;
  const std::vector<Route>& routes_;
  std::mt19937_64 rng_;
  std::vector<double> end_s_;  // each placed walker's nominal arrival
};

}  // namespace

WalkStats walk_stats(const Recording& walks, const WalkStatsOptions& options) {
  const double period = options.period_s;
  // Moments are times over the period: without a usable period nothing can be counted.
  if (!(period > 0.0 && std::isfinite(period))) return {};
  const auto one_period = [&](double dt) { return std::fabs(dt - period) <= kPeriodTolerance * period; };
  const std::vector<Track>& tracks = walks.tracks;

  // Each sample's step velocity: to the next sample, or from the one before at a track's end.
  std::vector<std::vector<std::optional<Point2D>>> velocity(tracks.size());
  std::vector<std::vector<double>> nearest(tracks.size());  // infinity when alone
  std::vector<Entry> entries;
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    const std::vector<Sample>& s = tracks[t].samples;
    velocity[t].resize(s.size());
    nearest[t].assign(s.size(), kInfinity);
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (k + 1 < s.size() && one_period(s[k + 1].time_s - s[k].time_s)) {
        velocity[t][k] = (1.0 / (s[k + 1].time_s - s[k].time_s)) * (s[k + 1].position - s[k].position);
      } else if (k > 0 && one_period(s[k].time_s - s[k - 1].time_s)) {
        velocity[t][k] = (1.0 / (s[k].time_s - s[k - 1].time_s)) * (s[k].position - s[k - 1].position);
      }
      if (std::isfinite(s[k].time_s)) entries.push_back({std::llround(s[k].time_s / period), t, k});
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.moment != b.moment ? a.moment < b.moment : (a.track != b.track ? a.track < b.track : a.index < b.index);
  });

  const auto walking = [&](const Entry& e) {
    const std::optional<Point2D>& v = velocity[e.track][e.index];
    return v && norm(*v) >= options.walking_m_s;
  };
  const auto position = [&](const Entry& e) { return tracks[e.track].samples[e.index].position; };

  WalkStats stats;
  std::vector<double> people;
  std::vector<double> nearest_m;
  std::vector<double> stranger_m;
  std::size_t companions = 0;
  for (std::size_t first = 0; first < entries.size();) {
    std::size_t last = first;
    while (last < entries.size() && entries[last].moment == entries[first].moment) ++last;
    const std::span<const Entry> moment(entries.data() + first, last - first);
    people.push_back(static_cast<double>(moment.size()));
    if (moment.size() >= 2) {
      for (const Entry& me : moment) {
        double best = kInfinity;
        bool best_is_companion = false;
        double stranger = kInfinity;
        for (const Entry& other : moment) {
          if (&other == &me) continue;
          const double d = norm(position(other) - position(me));
          const bool companion = d < options.free_m && walking(me) && walking(other) &&
                                 norm(*velocity[me.track][me.index] - *velocity[other.track][other.index]) <
                                     options.companion_m_s;
          if (d < best) {
            best = d;
            best_is_companion = companion;
          }
          if (!companion) stranger = std::min(stranger, d);
        }
        nearest[me.track][me.index] = best;
        nearest_m.push_back(best);
        if (best_is_companion) ++companions;
        if (stranger < kInfinity) stranger_m.push_back(stranger);
      }
    }
    first = last;
  }

  std::vector<double> speed;
  std::vector<double> walking_speed;
  std::vector<double> free_speed;
  std::vector<double> curvature;
  std::vector<double> smooth_curvature;
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    const std::vector<Sample>& s = tracks[t].samples;
    for (std::size_t k = 0; k + 1 < s.size(); ++k) {
      const double dt = s[k + 1].time_s - s[k].time_s;
      if (!one_period(dt)) continue;
      const double v = norm(s[k + 1].position - s[k].position) / dt;
      speed.push_back(v);
      if (v < options.walking_m_s) continue;
      walking_speed.push_back(v);
      if (nearest[t][k] >= options.free_m && nearest[t][k + 1] >= options.free_m) free_speed.push_back(v);
    }
    // Contiguous runs of samples one period apart: triples never straddle a gap.
    std::vector<std::size_t> run(s.size(), 0);
    for (std::size_t k = 1; k < s.size(); ++k) run[k] = run[k - 1] + (one_period(s[k].time_s - s[k - 1].time_s) ? 0 : 1);
    const auto turning = [&](std::size_t span, std::vector<double>& out) {
      const double step_s = static_cast<double>(span) * period;
      for (std::size_t k = 0; k + 2 * span < s.size(); ++k) {
        if (run[k] != run[k + 2 * span]) continue;
        const Point2D d1 = s[k + span].position - s[k].position;
        const Point2D d2 = s[k + 2 * span].position - s[k + span].position;
        if (norm(d1) < options.walking_m_s * step_s || norm(d2) < options.walking_m_s * step_s) continue;
        // The circle through the three points; a full reversal's is the one on the step.
        const double chord = norm(d1 + d2);
        out.push_back(chord > 1e-12 ? 2.0 * std::fabs(cross(d1, d2)) / (norm(d1) * norm(d2) * chord) : 2.0 / norm(d1));
      }
    };
    turning(1, curvature);
    turning(std::max<std::size_t>(1, options.smooth_span), smooth_curvature);
  }

  stats.moments = people.size();
  stats.people = quartiles(people);
  stats.speed_m_s = quartiles(speed);
  stats.walking_speed_m_s = quartiles(walking_speed);
  stats.free_speed_m_s = quartiles(free_speed);
  stats.nearest_m = quartiles(nearest_m);
  stats.stranger_nearest_m = quartiles(stranger_m);
  stats.companion_share =
      nearest_m.empty() ? 0.0 : static_cast<double>(companions) / static_cast<double>(nearest_m.size());
  stats.curvature_per_m = quartiles(curvature);
  stats.smooth_curvature_per_m = quartiles(smooth_curvature);
  return stats;
}

Result<Recording> sample_crowd(Crowd& crowd, double duration_s, double period_s) {
  if (!(period_s > 0.0 && std::isfinite(period_s)) || !(duration_s > 0.0 && std::isfinite(duration_s))) {
    return Error::format(Errc::invalid_argument, "sample_crowd: period %g s and duration %g s must be positive",
                         period_s, duration_s);
  }
  Recording out;
  out.name = "simulated";
  out.frame_step = 1;
  // The track each person is on while visible; none once out of sight.
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> open(crowd.size(), kNone);
  const double start_s = crowd.time_s();
  // 1e-9: a duration that is a whole number of periods keeps its last sample.
  const auto count = static_cast<std::size_t>(std::floor(duration_s / period_s + 1e-9));
  for (std::size_t k = 0; k <= count; ++k) {
    crowd.advance(start_s + static_cast<double>(k) * period_s, nullptr);
    for (std::size_t i = 0; i < crowd.size(); ++i) {
      const PersonState p = crowd.state(i);
      if (!p.visible) {
        open[i] = kNone;
        continue;
      }
      if (open[i] == kNone) {
        open[i] = out.tracks.size();
        out.tracks.push_back({static_cast<std::int64_t>(i), {}});
      }
      out.tracks[open[i]].samples.push_back({crowd.time_s(), p.position});
    }
  }
  return out;
}

Result<CrowdConfig> matched_crowd(const Recording& recording, std::uint64_t seed, const MatchedCrowdOptions& options) {
  const Summary summary = summarize(recording);
  if (Status s = check_matched(recording, summary, options); !s) return s.error();
  std::size_t people = options.people;
  if (people == 0) {
    std::vector<double> counts;
    for (const FrameCount& f : people_per_frame(recording)) counts.push_back(static_cast<double>(f.people));
    people = static_cast<std::size_t>(std::llround(quartiles(counts).median));
  }
  // A slot keeps one walk going, alone or as a pair: a share s of people in pairs is pairs on
  // s / (2 - s) of the walks, 1 + s / (2 - s) people per slot.
  const double pair_chance = options.pair_share / (2.0 - options.pair_share);
  const auto slots = static_cast<std::size_t>(std::llround(static_cast<double>(people) / (1.0 + pair_chance)));
  if (slots == 0) return Error(Errc::invalid_argument, "matched_crowd: no people");

  CrowdConfig config;
  config.behaviour = Behaviour::social;
  const Floor floor{summary.extent.min, summary.extent.max};
  config.walls = floor.walls();
  // The recorded routes long enough to walk; none when asked for none.
  std::vector<Route> routes;
  if (options.recorded_routes) {
    Result<std::vector<Route>> recorded = recorded_routes(recording);
    if (!recorded) return recorded.error();
    routes = std::move(*recorded);
  }
  WalkerPlan plan(config, floor, routes, seed);
  if (Status s = plan.run(slots, pair_chance, options.duration_s); !s) return s.error();
  return config;
}

}  // namespace sen3bot::crowd
