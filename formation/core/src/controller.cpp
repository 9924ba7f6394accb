#include "sen3bot/formation/controller.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "sen3bot/geometry/point_math.hpp"

namespace sen3bot::formation {

namespace {


Vec2 rotate(Vec2 a, double angle) noexcept {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  return {c * a.x_m - s * a.y_m, s * a.x_m + c * a.y_m};
}

// The barrier's speed at distance h past its zero: 1/h - 1/influence, unbounded as h -> 0 so a
// continuous-time trajectory never reaches the zero. Inside the zero (a start too close, or a
// latency overshoot) it stays at its value for a millimetre.
double barrier(double h, double influence) noexcept {
  if (h >= influence) return 0.0;
  return 1.0 / std::max(h, 1e-3) - 1.0 / influence;
}

// Periodic difference in (-period/2, period/2].
double wrap(double d, double period) noexcept {
  d = std::fmod(d, period);
  if (d > 0.5 * period) d -= period;
  if (d <= -0.5 * period) d += period;
  return d;
}

constexpr std::array<Gains, 6> kDefaultGains = {{
    {0.6, 0.6, 0.08, 0.0},
    {0.6, 0.6, 0.08, std::numbers::pi / 3.0},
    {0.6, 0.6, 0.08, -std::numbers::pi / 3.0},
    {1.0, 0.6, 0.08, std::numbers::pi / 3.0},
    {1.0, 0.6, 0.08, -std::numbers::pi / 3.0},
    {0.3, 0.3, 0.16, 0.0},
}};

Status config_error(const std::string& what) { return Error(Errc::config, "formation: " + what); }

}  // namespace

std::span<const Gains> default_gain_sets() noexcept { return kDefaultGains; }

// --- configuration -------------------------------------------------------------------------------

Status Controller::configure(const ControllerConfig& config) {
  configured_ = false;
  const auto finite = [](double v) { return std::isfinite(v); };
  if (config.robots == 0 || config.robots > kMaxRobots)
    return config_error("robots: 1 to " + std::to_string(kMaxRobots) + ", got " + std::to_string(config.robots));
  if (!finite(config.offset_m) || config.offset_m <= 0.0) return config_error("offset_m must be > 0");
  if (!finite(config.radius_m) || config.radius_m <= 0.0) return config_error("radius_m must be > 0");
  if (!finite(config.margin_m) || config.margin_m < 0.0) return config_error("margin_m must be >= 0");
  if (!finite(config.influence_m) || config.influence_m <= 0.0) return config_error("influence_m must be > 0");
  const Workspace& w = config.workspace;
  if (!(w.x0_m < w.x1_m) || !(w.y0_m < w.y1_m)) return config_error("workspace: x0 < x1 and y0 < y1");
  if (config.obstacle_count > kMaxObstacles) return config_error("obstacles: at most " + std::to_string(kMaxObstacles));
  for (std::size_t i = 0; i < config.obstacle_count; ++i)
    if (!finite(config.obstacles[i].radius_m) || config.obstacles[i].radius_m <= 0.0 ||
        !finite(config.obstacles[i].centre.x_m) || !finite(config.obstacles[i].centre.y_m))
      return config_error("obstacles[" + std::to_string(i) + "]: a finite centre and a radius > 0");
  if (config.gain_set_count > kMaxGainSets) return config_error("gain_sets: at most " + std::to_string(kMaxGainSets));
  if (!(config.eta > 0.0 && config.eta <= 1.0)) return config_error("eta: in (0, 1]");
  if (!(config.mu > 0.0 && config.mu < 1.0)) return config_error("mu: in (0, 1)");
  if (!finite(config.min_dwell_s) || config.min_dwell_s < 0.0) return config_error("min_dwell_s must be >= 0");
  if (!finite(config.settled_v) || config.settled_v < 0.0) return config_error("settled_v must be >= 0");
  if (!finite(config.v_max_m_s) || config.v_max_m_s <= 0.0) return config_error("v_max_m_s must be > 0");
  if (!finite(config.w_max_rad_s) || config.w_max_rad_s <= 0.0) return config_error("w_max_rad_s must be > 0");
  if (!finite(config.target_saturation_m) || config.target_saturation_m <= 0.0)
    return config_error("target_saturation_m must be > 0");

  config_ = config;
  if (config.gain_set_count == 0) {
    gain_count_ = kDefaultGains.size();
    std::copy(kDefaultGains.begin(), kDefaultGains.end(), gains_.begin());
  } else {
    gain_count_ = config.gain_set_count;
    std::copy_n(config.gain_sets.begin(), gain_count_, gains_.begin());
  }
  for (std::size_t g = 0; g < gain_count_; ++g) {
    const Gains& k = gains_[g];
    if (!(k.attract > 0.0) || !(k.spacing >= 0.0) || !(k.repel > 0.0) || !finite(k.swirl_rad) ||
        std::fabs(k.swirl_rad) >= std::numbers::pi / 2.0 || !finite(k.attract) || !finite(k.spacing) || !finite(k.repel))
      return config_error("gain_sets[" + std::to_string(g) +
                          "]: attract > 0, spacing >= 0, repel > 0, |swirl_rad| < pi/2 (the barrier must still push apart)");
  }

  // Where a P may stand: its circle (radius + offset, which holds the body circle about the
  // axle wherever the robot points) clear of the walls and obstacles by the margin.
  const double keep = config.radius_m + config.offset_m + config.margin_m;
  // The task's set lies beyond every barrier's reach: there the field is the task's alone, so
  // the set stays an equilibrium (docs/formation.md).
  const double reach = config.influence_m;
  const auto clear = [&](Vec2 p) {
    const Workspace grown{w.x0_m + reach, w.y0_m + reach, w.x1_m - reach, w.y1_m - reach};
    if (p.x_m - grown.x0_m < keep || grown.x1_m - p.x_m < keep || p.y_m - grown.y0_m < keep || grown.y1_m - p.y_m < keep)
      return false;
    for (std::size_t i = 0; i < config.obstacle_count; ++i)
      if (norm(p - config.obstacles[i].centre) < config.obstacles[i].radius_m + keep + reach) return false;
    return true;
  };
  const double apart = 2.0 * (config.radius_m + config.offset_m) + config.margin_m + reach;

  curve_count_ = 0;
  curve_length_ = 0.0;
  if (config.task == TaskKind::targets) {
    for (std::size_t i = 0; i < config.robots; ++i) {
      if (!finite(config.targets[i].x_m) || !finite(config.targets[i].y_m) || !clear(config.targets[i]))
        return config_error("targets[" + std::to_string(i) + "]: within the workspace, " + std::to_string(keep + reach) +
                            " m clear of its walls and obstacles");
      for (std::size_t j = 0; j < i; ++j)
        if (norm(config.targets[i] - config.targets[j]) < apart)
          return config_error("targets[" + std::to_string(j) + "] and [" + std::to_string(i) + "] closer than " +
                              std::to_string(apart) + " m");
    }
  } else {
    if (!finite(config.along_speed_m_s) || config.along_speed_m_s == 0.0)
      return config_error("along_speed_m_s must be finite and not 0");
    if (Status s = trace_curve(); !s) return s;
    for (std::size_t k = 0; k < curve_count_; ++k)
      if (!clear(curve_[k]))
        return config_error("curve: passes within " + std::to_string(keep + reach) + " m of a wall or obstacle near (" +
                            std::to_string(curve_[k].x_m) + ", " + std::to_string(curve_[k].y_m) + ")");
    if (config.task == TaskKind::leader) {
      for (std::size_t i = 1; i < config.robots; ++i) {
        const Vec2 o = config.offsets[i];
        if (!finite(o.x_m) || !finite(o.y_m) || norm(o) < apart)
          return config_error("offsets[" + std::to_string(i) + "]: finite and at least " + std::to_string(apart) +
                              " m from the leader");
        for (std::size_t j = 1; j < i; ++j)
          if (norm(o - config.offsets[j]) < apart)
            return config_error("offsets[" + std::to_string(j) + "] and [" + std::to_string(i) + "] closer than " +
                                std::to_string(apart) + " m");
        for (std::size_t k = 0; k < curve_count_; ++k)
          if (!clear(curve_[k] + o))
            return config_error("offsets[" + std::to_string(i) + "]: the follower's path leaves the workspace near (" +
                                std::to_string(curve_[k].x_m + o.x_m) + ", " + std::to_string(curve_[k].y_m + o.y_m) + ")");
      }
    } else if (config.robots > 1 && curve_length_ / static_cast<double>(config.robots) < apart) {
      return config_error("curve: too short for " + std::to_string(config.robots) + " robots " + std::to_string(apart) +
                          " m apart");
    }
  }
  configured_ = true;
  std::array<Pose, kMaxRobots> none{};
  reset(std::span<const Pose>(none.data(), config_.robots), 0.0);
  return Status::success();
}

// Follows V = {p = 0} from curve_start's foot on it, counter-clockwise (along J grad p), back
// to the start: once to measure it, once more to place kCurveSamples points evenly by length.
Status Controller::trace_curve() {
  nav::Point2D start;
  if (!nav::project_onto_curve(config_.curve, config_.curve_start, start))
    return config_error("curve: no point of the curve near curve_start");
  const auto tangent = [&](Vec2 at) -> Vec2 {
    const nav::Point2D g = config_.curve.gradient(at.x_m, at.y_m);
    const double n = std::hypot(g.x_m, g.y_m);
    if (!(n > 1e-12)) return {0.0, 0.0};
    return {-g.y_m / n, g.x_m / n};
  };
  const auto walk = [&](Vec2 from, double step) -> Vec2 {
    const Vec2 k1 = tangent(from);
    const Vec2 k2 = tangent(from + (0.5 * step) * k1);
    Vec2 next = from + step * k2;
    nav::Point2D on;
    if (nav::project_onto_curve(config_.curve, next, on)) next = on;
    return next;
  };
  const Vec2 origin = start;
  constexpr double kProbeStep = 0.005;
  constexpr std::size_t kMaxProbeSteps = 200'000;  // 1 km of curve
  double length = 0.0;
  Vec2 at = origin;
  bool closed = false;
  for (std::size_t i = 0; i < kMaxProbeSteps; ++i) {
    if (norm(tangent(at)) == 0.0) return config_error("curve: its gradient vanishes on it (a singular point)");
    const Vec2 next = walk(at, kProbeStep);
    length += norm(next - at);
    at = next;
    if (length > 20.0 * kProbeStep && norm(at - origin) < 1.5 * kProbeStep) {
      length += norm(origin - at);
      closed = true;
      break;
    }
  }
  if (!closed) return config_error("curve: not a closed curve (patrol and leader tasks go round one)");
  const double step = length / static_cast<double>(kCurveSamples);
  at = origin;
  double s = 0.0;
  for (std::size_t k = 0; k < kCurveSamples; ++k) {
    curve_[k] = at;
    curve_s_[k] = s;
    // Smaller sub-steps keep the samples on the curve where it bends.
    Vec2 next = at;
    for (int sub = 0; sub < 4; ++sub) next = walk(next, 0.25 * step);
    s += norm(next - at);
    at = next;
  }
  curve_count_ = kCurveSamples;
  // The last sample's chord back to the first closes the loop; its length ends the arc.
  curve_length_ = curve_s_[kCurveSamples - 1] + norm(curve_[0] - curve_[kCurveSamples - 1]);
  return Status::success();
}

// --- the curve's coordinate -------------------------------------------------------------------------

Controller::Along Controller::locate(Vec2 p) const noexcept {
  // Coarse then fine: every 8th sample, then the 16 around the best, then the foot on the two
  // segments beside it. Enough for a curve whose branches are farther apart than 8 samples.
  constexpr std::size_t kStride = 8;
  std::size_t best = 0;
  double best_d = 1e300;
  for (std::size_t k = 0; k < curve_count_; k += kStride) {
    const Vec2 d = curve_[k] - p;
    const double dd = dot(d, d);
    if (dd < best_d) best_d = dd, best = k;
  }
  const std::size_t n = curve_count_;
  const std::size_t centre = best;
  for (std::size_t o = 1; o <= kStride; ++o)
    for (const std::size_t k : {(centre + o) % n, (centre + n - o) % n}) {
      const Vec2 d = curve_[k] - p;
      const double dd = dot(d, d);
      if (dd < best_d) best_d = dd, best = k;
    }
  Along out;
  double best_seg = 1e300;
  for (const std::size_t a : {(best + n - 1) % n, best}) {
    const std::size_t b = (a + 1) % n;
    const Vec2 ab = curve_[b] - curve_[a];
    const double len2 = dot(ab, ab);
    const double t = len2 > 0.0 ? std::clamp(dot(p - curve_[a], ab) / len2, 0.0, 1.0) : 0.0;
    const Vec2 foot = curve_[a] + t * ab;
    const double dd = dot(p - foot, p - foot);
    if (dd < best_seg) {
      best_seg = dd;
      const double seg_len = b == 0 ? curve_length_ - curve_s_[a] : curve_s_[b] - curve_s_[a];
      out.s = std::fmod(curve_s_[a] + t * seg_len, curve_length_);
      const double l = std::sqrt(len2);
      out.tangent = l > 0.0 ? (1.0 / l) * ab : Vec2{1.0, 0.0};
    }
  }
  return out;
}

Vec2 Controller::curve_at(double s) const noexcept {
  s = std::fmod(s, curve_length_);
  if (s < 0.0) s += curve_length_;
  const auto it = std::upper_bound(curve_s_.begin(), curve_s_.begin() + static_cast<std::ptrdiff_t>(curve_count_), s);
  const std::size_t a = static_cast<std::size_t>(it - curve_s_.begin()) - 1;
  const std::size_t b = (a + 1) % curve_count_;
  const double seg_len = b == 0 ? curve_length_ - curve_s_[a] : curve_s_[b] - curve_s_[a];
  const double t = seg_len > 0.0 ? (s - curve_s_[a]) / seg_len : 0.0;
  return curve_[a] + t * (curve_[b] - curve_[a]);
}

// --- the field ----------------------------------------------------------------------------------------

void Controller::prepare(std::span<const Vec2> p) const noexcept {
  const std::size_t n = config_.robots;
  if (config_.task == TaskKind::targets) return;
  const std::size_t on_curve = config_.task == TaskKind::patrol ? n : 1;
  for (std::size_t i = 0; i < on_curve; ++i) {
    const Along a = locate(p[i]);
    State& st = state_[i];
    st.s = a.s;
    // p is close to a signed distance near V (sgp.hpp); its gradient's direction is the normal.
    const nav::Point2D g = config_.curve.gradient(p[i].x_m, p[i].y_m);
    const double gn = std::hypot(g.x_m, g.y_m);
    st.normal = gn > 1e-12 ? Vec2{g.x_m / gn, g.y_m / gn} : Vec2{-a.tangent.y_m, a.tangent.x_m};
    st.distance = gn > 1e-12 ? config_.curve.value(p[i].x_m, p[i].y_m) / gn : 0.0;
    // Travel along J n (counter-clockwise, the trace's direction), its sign the along speed's.
    st.tangent = {-st.normal.y_m, st.normal.x_m};
  }
  if (config_.task == TaskKind::patrol) {
    // The team's phase: the circular mean of each robot's position less its slot.
    double c = 0.0, s = 0.0;
    const double to_angle = 2.0 * std::numbers::pi / curve_length_;
    for (std::size_t i = 0; i < n; ++i) {
      const double a = (state_[i].s - slot_s_[i]) * to_angle;
      c += std::cos(a);
      s += std::sin(a);
    }
    double mean = std::atan2(s, c) / to_angle;
    if (mean < 0.0) mean += curve_length_;
    mean_s_ = mean;
    for (std::size_t i = 0; i < n; ++i) state_[i].spacing = wrap(state_[i].s - slot_s_[i] - mean_s_, curve_length_);
  }
}

void Controller::task_field(std::span<const Vec2> p, const Gains& k, std::span<Vec2> u) const noexcept {
  const std::size_t n = config_.robots;
  const double along = config_.along_speed_m_s;
  switch (config_.task) {
    case TaskKind::targets:
      for (std::size_t i = 0; i < n; ++i) {
        const Vec2 e = p[i] - config_.targets[i];
        const double scale = std::max(1.0, norm(e) / config_.target_saturation_m);
        u[i] = (-k.attract / scale) * e;
      }
      break;
    case TaskKind::patrol:
      for (std::size_t i = 0; i < n; ++i) {
        const State& st = state_[i];
        // Ahead of its slot: slower; behind: faster. Kept within twice the along speed so the
        // spacing never turns the team around the curve.
        const double speed = std::clamp(along - k.spacing * st.spacing, -2.0 * std::fabs(along), 2.0 * std::fabs(along));
        u[i] = (-k.attract * st.distance) * st.normal + speed * st.tangent;
      }
      break;
    case TaskKind::leader: {
      const State& st = state_[0];
      u[0] = (-k.attract * st.distance) * st.normal + along * st.tangent;
      for (std::size_t i = 1; i < n; ++i) {
        const Vec2 e = p[i] - p[0] - config_.offsets[i];
        const double scale = std::max(1.0, norm(e) / config_.target_saturation_m);
        u[i] = u[0] + (-k.attract / scale) * e;
      }
      break;
    }
  }
}

void Controller::barrier_field(std::span<const Vec2> p, const Gains& k, std::span<Vec2> u, double* min_h) const noexcept {
  const std::size_t n = config_.robots;
  const double body = config_.radius_m + config_.offset_m;
  const double pair_zero = 2.0 * body + config_.margin_m;
  const double keep = body + config_.margin_m;
  const double inf = config_.influence_m;
  double lowest = 1e300;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec2 d = p[i] - p[j];
      const double dist = norm(d);
      const double h = dist - pair_zero;
      lowest = std::min(lowest, h);
      const double m = k.repel * barrier(h, inf);
      if (m == 0.0) continue;
      const Vec2 dir = dist > 1e-9 ? (1.0 / dist) * d : Vec2{1.0, 0.0};
      // Both turn the same way: they pass each other on the same side.
      u[i] = u[i] + m * rotate(dir, k.swirl_rad);
      u[j] = u[j] + m * rotate(-1.0 * dir, k.swirl_rad);
    }
    const Workspace& w = config_.workspace;
    const double walls[4] = {p[i].x_m - w.x0_m - keep, w.x1_m - p[i].x_m - keep, p[i].y_m - w.y0_m - keep,
                             w.y1_m - p[i].y_m - keep};
    constexpr Vec2 inward[4] = {{1.0, 0.0}, {-1.0, 0.0}, {0.0, 1.0}, {0.0, -1.0}};
    for (int wi = 0; wi < 4; ++wi) {
      lowest = std::min(lowest, walls[wi]);
      const double m = k.repel * barrier(walls[wi], inf);
      if (m != 0.0) u[i] = u[i] + m * inward[wi];
    }
    for (std::size_t o = 0; o < config_.obstacle_count; ++o) {
      const Obstacle& ob = config_.obstacles[o];
      const Vec2 d = p[i] - ob.centre;
      const double dist = norm(d);
      const double h = dist - ob.radius_m - keep;
      lowest = std::min(lowest, h);
      const double m = k.repel * barrier(h, inf);
      if (m == 0.0) continue;
      const Vec2 dir = dist > 1e-9 ? (1.0 / dist) * d : Vec2{1.0, 0.0};
      u[i] = u[i] + m * rotate(dir, k.swirl_rad);
    }
  }
  if (min_h != nullptr) *min_h = lowest;
}

void Controller::field_prepared(std::span<const Vec2> p, std::size_t gain_set, std::span<Vec2> u, double* min_h) const noexcept {
  const Gains& k = gains_[std::min(gain_set, gain_count_ - 1)];
  task_field(p, k, u);
  barrier_field(p, k, u, min_h);
}

// <grad V, u>: V's gradient is, per robot, e_i (targets), d_i n_i + e_i t_i (patrol: distance to
// the curve and spacing error; the spacing errors sum to zero, so the mean phase's own motion
// drops out), d_0 n_0 and e_i = P_i - P_0 - o_i (leader: each follower's error also moves with
// the leader, hence -sum e_i on u_0).
double Controller::decrease_prepared(std::span<const Vec2> p, std::span<const Vec2> u) const noexcept {
  const std::size_t n = config_.robots;
  double l = 0.0;
  switch (config_.task) {
    case TaskKind::targets:
      for (std::size_t i = 0; i < n; ++i) l += dot(p[i] - config_.targets[i], u[i]);
      break;
    case TaskKind::patrol: {
      for (std::size_t i = 0; i < n; ++i) {
        const State& st = state_[i];
        l += st.distance * dot(st.normal, u[i]) + st.spacing * dot(st.tangent, u[i]);
      }
      break;
    }
    case TaskKind::leader: {
      const State& st = state_[0];
      l += st.distance * dot(st.normal, u[0]);
      for (std::size_t i = 1; i < n; ++i) {
        const Vec2 e = p[i] - p[0] - config_.offsets[i];
        l += dot(e, u[i] - u[0]);
      }
      break;
    }
  }
  return l;
}

double Controller::lyapunov_prepared(std::span<const Vec2> p) const noexcept {
  const std::size_t n = config_.robots;
  double v = 0.0;
  switch (config_.task) {
    case TaskKind::targets:
      for (std::size_t i = 0; i < n; ++i) {
        const Vec2 e = p[i] - config_.targets[i];
        v += 0.5 * dot(e, e);
      }
      break;
    case TaskKind::patrol:
      for (std::size_t i = 0; i < n; ++i)
        v += 0.5 * (state_[i].distance * state_[i].distance + state_[i].spacing * state_[i].spacing);
      break;
    case TaskKind::leader:
      v = 0.5 * state_[0].distance * state_[0].distance;
      for (std::size_t i = 1; i < n; ++i) {
        const Vec2 e = p[i] - p[0] - config_.offsets[i];
        v += 0.5 * dot(e, e);
      }
      break;
  }
  return v;
}

// rho: a share eta of what the nominal task field alone would take off V here. It is zero
// exactly on the task's set and independent of the gains in force.
double Controller::rho_prepared(std::span<const Vec2> p) const noexcept {
  std::array<Vec2, kMaxRobots> u{};
  task_field(p, gains_[0], std::span<Vec2>(u.data(), config_.robots));
  return config_.eta * std::max(0.0, -decrease_prepared(p, std::span<const Vec2>(u.data(), config_.robots)));
}

void Controller::field(std::span<const Vec2> p, std::size_t gain_set, std::span<Vec2> u) const noexcept {
  prepare(p);
  field_prepared(p, gain_set, u, nullptr);
}

double Controller::lyapunov(std::span<const Vec2> p) const noexcept {
  prepare(p);
  return lyapunov_prepared(p);
}

double Controller::decrease(std::span<const Vec2> p, std::size_t gain_set) const noexcept {
  prepare(p);
  std::array<Vec2, kMaxRobots> u{};
  field_prepared(p, gain_set, std::span<Vec2>(u.data(), config_.robots), nullptr);
  return decrease_prepared(p, std::span<const Vec2>(u.data(), config_.robots));
}

double Controller::rho(std::span<const Vec2> p) const noexcept {
  prepare(p);
  return rho_prepared(p);
}

Vec2 Controller::desired_prepared(std::span<const Vec2> p, std::size_t robot) const noexcept {
  switch (config_.task) {
    case TaskKind::targets:
      return config_.targets[robot];
    case TaskKind::patrol:
      return curve_at(mean_s_ + slot_s_[robot]);
    case TaskKind::leader:
      if (robot == 0) return p[0] - state_[0].distance * state_[0].normal;
      return p[0] + config_.offsets[robot];
  }
  return p[robot];
}

Vec2 Controller::desired(std::span<const Vec2> p, std::size_t robot) const noexcept {
  prepare(p);
  return desired_prepared(p, robot);
}

double Controller::formation_error(std::span<const Vec2> p) const noexcept {
  prepare(p);
  double worst = 0.0;
  for (std::size_t i = 0; i < config_.robots; ++i) worst = std::max(worst, norm(p[i] - desired_prepared(p, i)));
  return worst;
}

// --- the run ----------------------------------------------------------------------------------------

void Controller::reset(std::span<const Pose> poses, double t_s) noexcept {
  active_ = 0;
  last_switch_s_ = -1e300;
  switches_ = 0;
  info_ = StepInfo{};
  info_.t_s = t_s;
  if (!configured_ || config_.task != TaskKind::patrol) return;
  // Slots in the robots' order along the curve, evenly spaced: nobody has to overtake.
  const std::size_t n = config_.robots;
  std::array<std::size_t, kMaxRobots> order{};
  std::array<double, kMaxRobots> s{};
  for (std::size_t i = 0; i < n; ++i) {
    order[i] = i;
    s[i] = locate(point_p(poses[i], config_.offset_m)).s;
  }
  // Insertion sort: at most kMaxRobots entries.
  for (std::size_t i = 1; i < n; ++i)
    for (std::size_t j = i; j > 0 && s[order[j]] < s[order[j - 1]]; --j) std::swap(order[j], order[j - 1]);
  for (std::size_t rank = 0; rank < n; ++rank)
    slot_s_[order[rank]] = curve_length_ * static_cast<double>(rank) / static_cast<double>(n);
}

const StepInfo& Controller::step(double t_s, std::span<const Pose> poses, std::span<Unicycle> commands) noexcept {
  const std::size_t n = config_.robots;
  info_.t_s = t_s;
  info_.switched = false;
  info_.unresolved = false;
  bool valid = configured_ && poses.size() >= n && commands.size() >= n;
  for (std::size_t i = 0; valid && i < n; ++i)
    valid = std::isfinite(poses[i].x_m) && std::isfinite(poses[i].y_m) && std::isfinite(poses[i].theta_rad);
  if (!valid) {
    for (Unicycle& c : commands) c = {};
    info_.scale = 0.0;
    return info_;
  }
  const std::span<Vec2> p(p_.data(), n);
  const std::span<Vec2> u(u_.data(), n);
  for (std::size_t i = 0; i < n; ++i) p[i] = point_p(poses[i], config_.offset_m);
  prepare(p);

  double min_h = 0.0;
  field_prepared(p, active_, u, &min_h);
  const double v = lyapunov_prepared(p);
  const double r = rho_prepared(p);
  double l = decrease_prepared(p, u);
  // The hybrid rule: jump when the decrease falls short of mu * rho.
  if (v > config_.settled_v && l > -config_.mu * r && t_s - last_switch_s_ >= config_.min_dwell_s) {
    const std::span<Vec2> trial(scratch_.data(), n);
    std::size_t best = active_;
    double best_l = l;
    for (std::size_t g = 0; g < gain_count_; ++g) {
      if (g == active_) continue;
      field_prepared(p, g, trial, nullptr);
      const double lg = decrease_prepared(p, trial);
      if (lg < best_l) best_l = lg, best = g;
    }
    info_.unresolved = best_l > -r;
    if (best != active_) {
      active_ = best;
      last_switch_s_ = t_s;
      ++switches_;
      info_.switched = true;
      field_prepared(p, active_, u, &min_h);
      l = best_l;
    }
  }

  for (std::size_t i = 0; i < n; ++i) commands[i] = to_unicycle(poses[i], u[i], config_.offset_m);
  const double f = common_scale(std::span<const Unicycle>(commands.data(), n), config_.v_max_m_s, config_.w_max_rad_s);
  for (std::size_t i = 0; i < n; ++i) commands[i] = {f * commands[i].v, f * commands[i].w};

  info_.lyapunov = v;
  info_.decrease = l;
  info_.rho = r;
  info_.scale = f;
  info_.gain_set = active_;
  info_.min_barrier_m = min_h;
  double worst = 0.0;
  for (std::size_t i = 0; i < n; ++i) worst = std::max(worst, norm(p[i] - desired_prepared(p, i)));
  info_.formation_error_m = worst;
  return info_;
}

}  // namespace sen3bot::formation
