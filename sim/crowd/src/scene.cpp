#include "sen3bot/crowd/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <system_error>
#include <utility>

#include "sen3bot/crowd/random.hpp"
#include "sen3bot/crowd/replay.hpp"
#include "sen3bot/msg/point_math.hpp"
#include "sen3bot/nav/map.hpp"

namespace sen3bot::crowd {
namespace {

using msg::norm;

// Rejection sampling gives up after this many draws for one person (or one robot path).
constexpr int kMaxDraws = 1000;

constexpr double kTimeLimitFactor = 3.0;  // CrowdNav: 25 s for 8 m at 1 m/s

// Simulated walkers (crossing, corridor, square).
constexpr double kSpeedMeanM_s = 1.3;    // Moussaïd et al. 2009
constexpr double kSpeedSdM_s = 0.26;     // Weidmann 1993
constexpr double kSpeedMinM_s = 0.5;
constexpr double kSpeedMaxM_s = 2.0;

// CrowdNav's circle_crossing (env.config).
constexpr double kCircleRadiusM = 4.0;
constexpr double kCircleHumanRadiusM = 0.3;
constexpr double kCircleSpeedM_s = 1.0;  // v_pref; also the scale of the jitter
constexpr double kCircleTimeLimitS = 25.0;
constexpr double kCircleHalfFloorM = 6.0;

// Recorded floors are rounded outwards to this, so their maps have round numbers.
constexpr double kFloorGridM = 0.5;

double time_limit_for(double length_m) { return std::ceil(kTimeLimitFactor * length_m / kRobotSpeedM_s); }

std::vector<Wall> border(const Extent& a) {
  const Point2D lo = a.min;
  const Point2D hi = a.max;
  return {{lo, {hi.x_m, lo.y_m}}, {{hi.x_m, lo.y_m}, hi}, {hi, {lo.x_m, hi.y_m}}, {{lo.x_m, hi.y_m}, lo}};
}

// The floor, its border walls, the robot facing its goal and the crowd's behaviour.
Scene base(std::string name, Extent area, Point2D start, Point2D goal, double time_limit_s, Behaviour behaviour) {
  Scene s;
  s.name = std::move(name);
  s.area = area;
  s.walls = border(area);
  const Point2D to_goal = goal - start;
  s.robot_start = {start.x_m, start.y_m, std::atan2(to_goal.y_m, to_goal.x_m)};
  s.robot_goal = goal;
  s.time_limit_s = time_limit_s;
  s.crowd.behaviour = behaviour;
  s.crowd.walls = s.walls;
  return s;
}

Point2D robot_start(const Scene& s) noexcept { return {s.robot_start.x_m, s.robot_start.y_m}; }

// Within the discomfort distance of the robot's start or goal (CrowdNav's check).
bool near_robot(const Scene& s, Point2D p, double radius_m) noexcept {
  const double gap = radius_m + kSceneRobotRadiusM + kDiscomfortM;
  return norm(p - robot_start(s)) < gap || norm(p - s.robot_goal) < gap;
}

// Walker `by` passes (or stands at) p's start when p appears, as far as its straight walk at
// between kSlowFactor and the model's cap of kFastFactor times its desired speed tells; the
// window is widened by twice the time either needs to walk the gap from rest (relaxation 0.5 s).
// Walkers held up by others still may: this keeps the common case out, not every case.
constexpr double kFastFactor = 1.3;  // SocialForceModel's max_speed_factor
constexpr double kSlowFactor = 0.7;
bool appears_on(const Person& p, const Person& by) noexcept {
  const double gap = p.radius_m + by.radius_m + kDiscomfortM;
  const Point2D a = by.start;
  const Point2D b = by.goals[0];
  if (msg::segment_distance(p.start, a, b) >= gap) return false;
  const double length = norm(b - a);
  const double along = length > 0.0 ? std::clamp(msg::dot(p.start - a, b - a) / length, 0.0, length) : 0.0;
  const double v = by.desired_speed_m_s;
  const double hold_s = 2.0 * gap / std::min(p.desired_speed_m_s, v);
  const double first_s = by.appear_s + std::max(0.0, along - gap) / (kFastFactor * v) - hold_s;
  const double last_s = by.appear_s + std::min(length, along + gap) / (kSlowFactor * v) + hold_s;
  return p.appear_s > first_s && p.appear_s < last_s;
}

bool start_taken(const Person& p, const std::vector<Person>& placed) noexcept {
  for (const Person& q : placed) {
    if (appears_on(p, q) || appears_on(q, p)) return true;
  }
  return false;
}

struct Walk {
  Point2D start;
  Point2D goal;
};

Error no_room(const char* scene, std::size_t placed, std::size_t wanted) {
  return Error::format(Errc::capacity, "scene '%s': room for only %zu of %zu people (%d draws each)", scene, placed,
                       wanted, kMaxDraws);
}

// `count` walkers whose walks come from draw(rng) (nullopt: a failed draw), each with a speed
// drawn first (so spacing does not bias it) and an appearance time in [0, window_s).
template <typename Draw>
Status add_walkers(Scene& s, std::size_t count, double window_s, std::mt19937_64& rng, Draw draw) {
  std::vector<Person>& people = s.crowd.people;
  people.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    Person p;
    p.radius_m = kWalkerRadiusM;
    p.desired_speed_m_s = draw_walker_speed(rng);
    p.goal_count = 1;
    p.leave_at_goal = true;
    bool placed = false;
    for (int attempt = 0; attempt < kMaxDraws && !placed; ++attempt) {
      const std::optional<Walk> walk = draw(rng);
      const double appear_s = uniform(rng, 0.0, window_s);
      if (!walk) continue;
      p.start = walk->start;
      p.goals[0] = walk->goal;
      p.appear_s = appear_s;
      placed = !near_robot(s, p.start, p.radius_m) && !near_robot(s, p.goals[0], p.radius_m) && !start_taken(p, people);
    }
    if (!placed) return no_room(s.name.c_str(), i, count);
    people.push_back(p);
  }
  return Status::success();
}

Result<Scene> circle(std::size_t count, Behaviour behaviour, std::mt19937_64& rng) {
  const double h = kCircleHalfFloorM;
  Scene s = base("circle", {{-h, -h}, {h, h}}, {0.0, -kCircleRadiusM}, {0.0, kCircleRadiusM}, kCircleTimeLimitS,
                 behaviour);
  std::vector<Person>& people = s.crowd.people;
  people.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    Person p;
    p.radius_m = kCircleHumanRadiusM;
    p.desired_speed_m_s = kCircleSpeedM_s;
    p.goal_count = 1;
    bool placed = false;
    for (int attempt = 0; attempt < kMaxDraws && !placed; ++attempt) {
      // CrowdNav's generate_circle_crossing_human, draw for draw.
      const double angle = unit_uniform(rng) * std::numbers::pi * 2.0;
      const double px_noise = (unit_uniform(rng) - 0.5) * p.desired_speed_m_s;
      const double py_noise = (unit_uniform(rng) - 0.5) * p.desired_speed_m_s;
      p.start = {kCircleRadiusM * std::cos(angle) + px_noise, kCircleRadiusM * std::sin(angle) + py_noise};
      placed = !near_robot(s, p.start, p.radius_m);
      for (const Person& q : people) {
        const double gap = p.radius_m + q.radius_m + kDiscomfortM;
        placed = placed && norm(p.start - q.start) >= gap && norm(p.start - q.goals[0]) >= gap;
      }
    }
    if (!placed) return no_room("circle", i, count);
    p.goals[0] = -p.start;  // through the centre to the opposite point
    people.push_back(p);
  }
  return s;
}

Result<Scene> crossing(std::size_t count, Behaviour behaviour, std::mt19937_64& rng) {
  constexpr double kLength = 12.0;
  constexpr double kWidth = 8.0;
  constexpr double kMaxSideways = 1.5;  // goal x within this of the start's: ~12 degrees off square
  const Point2D start{1.0, kWidth / 2.0};
  const Point2D goal{kLength - 1.0, kWidth / 2.0};
  const double length = norm(goal - start);
  Scene s = base("crossing", {{0.0, 0.0}, {kLength, kWidth}}, start, goal, time_limit_for(length), behaviour);
  const auto draw = [&](std::mt19937_64& r) -> std::optional<Walk> {
    const bool up = unit_uniform(r) < 0.5;
    const double x0 = uniform(r, 1.5, kLength - 1.5);
    const double x1 = uniform(r, std::max(kWallGapM, x0 - kMaxSideways), std::min(kLength - kWallGapM, x0 + kMaxSideways));
    const double y0 = up ? kWallGapM : kWidth - kWallGapM;
    return Walk{{x0, y0}, {x1, kWidth - y0}};
  };
  if (Status st = add_walkers(s, count, length / kRobotSpeedM_s, rng, draw); !st) return st.error();
  return s;
}

Result<Scene> corridor(std::size_t count, Behaviour behaviour, std::mt19937_64& rng) {
  constexpr double kLength = 20.0;
  constexpr double kWidth = 3.0;
  const Point2D start{2.0, kWidth / 2.0};
  const Point2D goal{kLength - 2.0, kWidth / 2.0};
  const double length = norm(goal - start);
  Scene s = base("corridor", {{0.0, 0.0}, {kLength, kWidth}}, start, goal, time_limit_for(length), behaviour);
  const auto draw = [&](std::mt19937_64& r) -> std::optional<Walk> {
    const bool east = unit_uniform(r) < 0.5;
    const double x0 = east ? kWallGapM : kLength - kWallGapM;
    const double y0 = uniform(r, kWallGapM, kWidth - kWallGapM);
    const double y1 = uniform(r, kWallGapM, kWidth - kWallGapM);
    return Walk{{x0, y0}, {kLength - x0, y1}};
  };
  if (Status st = add_walkers(s, count, length / kRobotSpeedM_s, rng, draw); !st) return st.error();
  return s;
}

Result<Scene> square(std::size_t count, Behaviour behaviour, std::mt19937_64& rng) {
  constexpr double kSide = 10.0;
  constexpr double kMinWalkM = 2.0;  // a walk, not a step round a corner
  const Point2D start{1.0, 1.0};
  const Point2D goal{kSide - 1.0, kSide - 1.0};
  const double length = norm(goal - start);
  Scene s = base("square", {{0.0, 0.0}, {kSide, kSide}}, start, goal, time_limit_for(length), behaviour);
  // Side 0 bottom, 1 right, 2 top, 3 left; t along it.
  const auto on_side = [](int side, double t) -> Point2D {
    constexpr double lo = kWallGapM;
    constexpr double hi = kSide - kWallGapM;
    switch (side) {
      case 0:
        return {t, lo};
      case 1:
        return {hi, t};
      case 2:
        return {t, hi};
      default:
        return {lo, t};
    }
  };
  const auto draw = [&](std::mt19937_64& r) -> std::optional<Walk> {
    const int from = std::min(3, static_cast<int>(unit_uniform(r) * 4.0));
    const int to = (from + 1 + std::min(2, static_cast<int>(unit_uniform(r) * 3.0))) % 4;
    const Point2D a = on_side(from, uniform(r, kWallGapM, kSide - kWallGapM));
    const Point2D b = on_side(to, uniform(r, kWallGapM, kSide - kWallGapM));
    if (norm(b - a) < kMinWalkM) return std::nullopt;
    return Walk{a, b};
  };
  if (Status st = add_walkers(s, count, length / kRobotSpeedM_s, rng, draw); !st) return st.error();
  return s;
}

// What Replay relies on, as Crowd::create checks it: a hand-built recording may break it.
Status check_tracks(const Recording& recording) noexcept {
  const std::string_view name = name_tail(recording.name);
  for (std::size_t i = 0; i < recording.tracks.size(); ++i) {
    const std::vector<Sample>& samples = recording.tracks[i].samples;
    if (samples.empty()) {
      return Error::format(Errc::invalid_argument, "%.*s: track %zu is empty", static_cast<int>(name.size()),
                           name.data(), i);
    }
    for (std::size_t k = 0; k < samples.size(); ++k) {
      if (!std::isfinite(samples[k].time_s) || !geometry::finite(samples[k].position) ||
          (k > 0 && !(samples[k].time_s > samples[k - 1].time_s))) {
        return Error::format(Errc::invalid_argument,
                             "%.*s: track %zu, sample %zu: not finite or not after the one before",
                             static_cast<int>(name.size()), name.data(), i, k);
      }
    }
  }
  return Status::success();
}

// The part [t_lo, t_hi] of the line p + t d inside the box (p inside it, d a unit vector).
std::pair<double, double> clip(Point2D p, Point2D d, const Extent& box) noexcept {
  double t_lo = -std::numeric_limits<double>::infinity();
  double t_hi = std::numeric_limits<double>::infinity();
  const std::array<std::array<double, 4>, 2> axes = {{{p.x_m, d.x_m, box.min.x_m, box.max.x_m},
                                                      {p.y_m, d.y_m, box.min.y_m, box.max.y_m}}};
  for (const auto& [q, dq, lo, hi] : axes) {
    if (std::fabs(dq) < 1e-12) continue;  // parallel to this pair of sides
    const double t1 = (lo - q) / dq;
    const double t2 = (hi - q) / dq;
    t_lo = std::max(t_lo, std::min(t1, t2));
    t_hi = std::min(t_hi, std::max(t1, t2));
  }
  return {t_lo, t_hi};
}

std::string file_stem(const std::string& name) {
  std::string stem = name.substr(name.find_last_of("/\\") == std::string::npos ? 0 : name.find_last_of("/\\") + 1);
  const std::size_t dot = stem.find_last_of('.');
  if (dot != std::string::npos && dot > 0) stem.resize(dot);
  for (char& c : stem) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    if (!keep) c = '_';
  }
  return stem.empty() ? std::string("scene") : stem;
}

// Whether the segment a-b touches the closed box [lo, hi] (Liang-Barsky clipping).
bool touches(Point2D a, Point2D b, Point2D lo, Point2D hi) noexcept {
  double t0 = 0.0;
  double t1 = 1.0;
  const Point2D d = b - a;
  const std::array<std::array<double, 2>, 4> sides = {{{-d.x_m, a.x_m - lo.x_m},
                                                       {d.x_m, hi.x_m - a.x_m},
                                                       {-d.y_m, a.y_m - lo.y_m},
                                                       {d.y_m, hi.y_m - a.y_m}}};
  for (const auto& [p, q] : sides) {
    if (p == 0.0) {
      if (q < 0.0) return false;  // parallel and outside
    } else if (p < 0.0) {
      t0 = std::max(t0, q / p);
    } else {
      t1 = std::min(t1, q / p);
    }
    if (t0 > t1) return false;
  }
  return true;
}

// On one side of the floor's border: the ring of outside cells stands for it.
bool on_border(const Wall& w, const Extent& area) noexcept {
  constexpr double kEps = 1e-9;
  const auto same = [](double u, double v) { return std::fabs(u - v) <= kEps; };
  return (same(w.a.x_m, area.min.x_m) && same(w.b.x_m, area.min.x_m)) ||
         (same(w.a.x_m, area.max.x_m) && same(w.b.x_m, area.max.x_m)) ||
         (same(w.a.y_m, area.min.y_m) && same(w.b.y_m, area.min.y_m)) ||
         (same(w.a.y_m, area.max.y_m) && same(w.b.y_m, area.max.y_m));
}

}  // namespace

double draw_walker_speed(std::mt19937_64& rng) noexcept {
  for (;;) {
    const double v = kSpeedMeanM_s + kSpeedSdM_s * standard_normal(rng);
    if (v >= kSpeedMinM_s && v <= kSpeedMaxM_s) return v;
  }
}

std::size_t default_people(std::string_view name) noexcept {
  if (name == "circle") return 5;
  if (name == "crossing" || name == "corridor" || name == "square") return 10;
  return 0;
}

Result<Scene> make_scene(const SceneOptions& options, std::uint64_t seed) {
  const std::string_view name = name_tail(options.name, 40);
  const int len = static_cast<int>(name.size());
  const char* text = name.data();
  constexpr Errc kBad = Errc::invalid_argument;
  if (options.name == "recorded") {
    if (!options.recording) return Error(kBad, "scene 'recorded' needs a recording");
    if (options.people != 0) {
      return Error::format(kBad, "scene 'recorded': its people are the recording's (people must be 0, not %zu)",
                           options.people);
    }
    if (options.behaviour && *options.behaviour != Behaviour::recorded) {
      return Error::format(kBad, "scene 'recorded': a recording is replayed as it was, not as %s",
                           to_string(*options.behaviour));
    }
    return recording_scene(options.recording, seed);
  }
  if (std::find(std::begin(kSceneNames), std::end(kSceneNames), options.name) == std::end(kSceneNames)) {
    return Error::format(kBad, "unknown scene '%.*s' (circle, crossing, corridor, square or recorded)", len, text);
  }
  if (options.recording) {
    return Error::format(kBad, "scene '%.*s' takes no recording (that is scene 'recorded')", len, text);
  }
  const Behaviour behaviour =
      options.behaviour.value_or(options.name == "circle" ? Behaviour::orca : Behaviour::social);
  if (behaviour != Behaviour::social && behaviour != Behaviour::blind && behaviour != Behaviour::orca) {
    return Error::format(kBad, "scene '%.*s': behaviour %s; simulated people are social, blind or orca", len, text,
                         to_string(behaviour));
  }
  if (options.people == 0) return Error::format(kBad, "scene '%.*s' needs at least one person", len, text);
  const std::size_t most = behaviour == Behaviour::orca ? kMaxOrcaAgents : kMaxWalkers;
  if (options.people > most) {
    return Error::format(Errc::capacity, "scene '%.*s': %zu people, at most %zu %s ones", len, text, options.people,
                         most, to_string(behaviour));
  }
  std::mt19937_64 rng(seed);
  if (options.name == "circle") return circle(options.people, behaviour, rng);
  if (options.name == "crossing") return crossing(options.people, behaviour, rng);
  if (options.name == "corridor") return corridor(options.people, behaviour, rng);
  return square(options.people, behaviour, rng);
}

Result<Scene> recording_scene(std::shared_ptr<const Recording> recording, std::uint64_t seed,
                              const RecordingSceneOptions& options) {
  if (!recording) return Error(Errc::invalid_argument, "recording_scene: no recording");
  const std::string_view name = name_tail(recording->name);
  const int name_len = static_cast<int>(name.size());
  if (!(options.margin_m >= 0.0 && std::isfinite(options.margin_m)) ||
      !(options.clear_m >= 0.0 && std::isfinite(options.clear_m))) {
    return Error::format(Errc::invalid_argument, "%.*s: margin %g m and clearance %g m must be finite and >= 0",
                         name_len, name.data(), options.margin_m, options.clear_m);
  }
  if (Status st = check_tracks(*recording); !st) return st.error();
  const Summary summary = summarize(*recording);
  if (summary.samples == 0) return Error::format(Errc::invalid_argument, "%.*s: no samples", name_len, name.data());
  const Result<Point2D> busiest = busiest_point(*recording, options.cell_m);
  if (!busiest) return busiest.error();

  const Point2D margin{options.margin_m, options.margin_m};
  const auto round_down = [](double v) { return std::floor(v / kFloorGridM) * kFloorGridM; };
  const auto round_up = [](double v) { return std::ceil(v / kFloorGridM) * kFloorGridM; };
  const Point2D lo = summary.extent.min - margin;
  const Point2D hi = summary.extent.max + margin;
  const Extent area{{round_down(lo.x_m), round_down(lo.y_m)}, {round_up(hi.x_m), round_up(hi.y_m)}};
  const Extent ends{area.min + Point2D{kWallGapM, kWallGapM}, area.max - Point2D{kWallGapM, kWallGapM}};
  const Point2D b = *busiest;
  if (!(b.x_m > ends.min.x_m && b.x_m < ends.max.x_m && b.y_m > ends.min.y_m && b.y_m < ends.max.y_m)) {
    return Error::format(Errc::invalid_argument,
                         "%.*s: the busiest point (%g, %g) m is within %g m of the walls; grow the margin", name_len,
                         name.data(), b.x_m, b.y_m, kWallGapM);
  }

  Replay replay(*recording);
  std::mt19937_64 rng(seed);
  double shortest_limit_s = std::numeric_limits<double>::infinity();
  bool fitted = false;
  for (int attempt = 0; attempt < kMaxDraws; ++attempt) {
    const double angle = unit_uniform(rng) * std::numbers::pi * 2.0;
    const double moment = unit_uniform(rng);
    const Point2D d{std::cos(angle), std::sin(angle)};
    const auto [t_lo, t_hi] = clip(b, d, ends);
    const Point2D start = b + t_lo * d;
    const Point2D goal = b + t_hi * d;
    const double limit_s = time_limit_for(t_hi - t_lo);
    shortest_limit_s = std::min(shortest_limit_s, limit_s);
    const double latest_s = summary.end_s - limit_s;
    if (latest_s < summary.start_s) continue;
    fitted = true;
    const double start_s = summary.start_s + (latest_s - summary.start_s) * moment;
    bool clear = true;
    for (std::size_t k = 0; k < replay.track_count() && clear; ++k) {
      const WalkerState at = replay.state_at(k, start_s);
      clear = !at.visible || (norm(at.position - start) >= options.clear_m && norm(at.position - goal) >= options.clear_m);
    }
    if (!clear) continue;
    Scene s = base(recording->name, area, start, goal, limit_s, Behaviour::recorded);
    s.crowd.recording = std::move(recording);
    s.crowd.recording_start_s = start_s;
    return s;
  }
  if (!fitted) {
    return Error::format(Errc::invalid_argument,
                         "%.*s: its %g s are shorter than the time limit (at least %g s through the busiest point)",
                         name_len, name.data(), summary.end_s - summary.start_s, shortest_limit_s);
  }
  return Error::format(Errc::capacity, "%.*s: no robot path through (%g, %g) m clear of people by %g m in %d draws",
                       name_len, name.data(), b.x_m, b.y_m, options.clear_m, kMaxDraws);
}

Result<std::string> write_scene_map(const Scene& scene, const std::string& dir, double resolution_m) {
  if (!(resolution_m > 0.0 && std::isfinite(resolution_m))) {
    return Error::format(Errc::invalid_argument, "scene map: resolution %g m is not positive and finite", resolution_m);
  }
  const Extent& area = scene.area;
  if (!geometry::finite(area.min) || !geometry::finite(area.max) || !(area.max.x_m > area.min.x_m) || !(area.max.y_m > area.min.y_m)) {
    return Error::format(Errc::invalid_argument, "scene map: the floor of '%s' is empty or not finite",
                         scene.name.c_str());
  }
  // The border ring: at least 2 cells so no ray slips through, and at least 0.1 m.
  const double ring = std::max(2.0, std::ceil(0.1 / resolution_m - 1e-9));
  const double cols = std::ceil((area.max.x_m - area.min.x_m) / resolution_m - 1e-9) + 2.0 * ring;
  const double rows = std::ceil((area.max.y_m - area.min.y_m) / resolution_m - 1e-9) + 2.0 * ring;
  constexpr double kMaxSide = 65536.0;  // parse_pgm's limit
  if (!(cols <= kMaxSide && rows <= kMaxSide && cols * rows <= static_cast<double>(nav::kMaxMapCells))) {
    return Error::format(Errc::capacity, "scene map: %g x %g cells of %g m, at most %zu cells of 65536 a side", cols,
                         rows, resolution_m, nav::kMaxMapCells);
  }
  const auto width = static_cast<std::size_t>(cols);
  const auto height = static_cast<std::size_t>(rows);
  const Point2D origin = area.min - Point2D{ring * resolution_m, ring * resolution_m};

  // Row 0 is the bottom (map frame); the image is written top row first.
  std::vector<bool> occupied(width * height, false);
  const auto centre = [&](std::size_t col, std::size_t row) {
    return origin + resolution_m * Point2D{static_cast<double>(col) + 0.5, static_cast<double>(row) + 0.5};
  };
  for (std::size_t row = 0; row < height; ++row) {
    for (std::size_t col = 0; col < width; ++col) {
      const Point2D c = centre(col, row);
      occupied[row * width + col] =
          c.x_m < area.min.x_m || c.x_m > area.max.x_m || c.y_m < area.min.y_m || c.y_m > area.max.y_m;
    }
  }
  for (const Wall& w : scene.walls) {
    if (!geometry::finite(w.a) || !geometry::finite(w.b) || on_border(w, area)) continue;
    // A nanometre of slack: a wall on a cell boundary blocks both cells on every machine, FMA or not.
    const double half = 0.5 * resolution_m + 1e-9;
    const auto cell_range = [&](double a, double b, double o, std::size_t n) {
      const double first = std::floor((std::min(a, b) - o) / resolution_m) - 1.0;
      const double last = std::floor((std::max(a, b) - o) / resolution_m) + 1.0;
      const double top = static_cast<double>(n) - 1.0;
      return std::pair{static_cast<std::size_t>(std::clamp(first, 0.0, top)),
                       static_cast<std::size_t>(std::clamp(last, 0.0, top))};
    };
    const auto [col0, col1] = cell_range(w.a.x_m, w.b.x_m, origin.x_m, width);
    const auto [row0, row1] = cell_range(w.a.y_m, w.b.y_m, origin.y_m, height);
    for (std::size_t row = row0; row <= row1; ++row) {
      for (std::size_t col = col0; col <= col1; ++col) {
        const Point2D c = centre(col, row);
        if (touches(w.a, w.b, c - Point2D{half, half}, c + Point2D{half, half})) occupied[row * width + col] = true;
      }
    }
  }

  const std::string stem = file_stem(scene.name);
  nav::OccupancyMap map(static_cast<int>(width), static_cast<int>(height), resolution_m, origin.x_m, origin.y_m);
  for (std::size_t row = 0; row < height; ++row)
    for (std::size_t col = 0; col < width; ++col)
      map.set(static_cast<int>(col), static_cast<int>(row), occupied[row * width + col] ? nav::kOccupiedOccupancy : 0);
  char comment[320];
  std::snprintf(comment, sizeof comment,
                "Sen3Bot crowd scene %s (write_scene_map): %zu x %zu cells of %.12g m; the free floor is\n"
                "x in [%.12g, %.12g] m, y in [%.12g, %.12g] m.",
                stem.c_str(), width, height, resolution_m, area.min.x_m, area.max.x_m, area.min.y_m, area.max.y_m);

  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Error::format(Errc::io, "%s: cannot create: %s", dir.c_str(), ec.message().c_str());
  const std::string yaml_path = (std::filesystem::path(dir) / stem).string() + ".yaml";
  if (Status st = nav::save_map(map, yaml_path, comment); !st) return st.error();
  return yaml_path;
}

}  // namespace sen3bot::crowd
