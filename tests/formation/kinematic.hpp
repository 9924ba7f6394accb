#pragma once
// A team of ideal unicycles closed round the formation controller: commands computed every
// control period from poses `latency_s` old, held, and integrated in small steps. The whole
// firmware on the simulated robots is tests/sim/formation_test.cpp's; this one is fast enough
// for many runs.
#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <vector>

#include "sen3bot/formation/controller.hpp"
#include "sen3bot/formation/examples.hpp"

namespace sen3bot::formation::testing {

struct KinematicResult {
  double min_axle_distance_m = 1e9;  // closest two body circles' centres came
  double min_wall_clearance_m = 1e9; // body circle to the workspace's edge
  double final_error_m = 1e9;        // formation_error at the end
  double worst_error_after_m = 0.0;  // worst formation error after converge_s
  double converge_s = -1.0;          // from here on the error stayed <= 0.05 m
  std::uint64_t switches = 0;
  std::vector<Pose> final_poses;
};

inline KinematicResult run_kinematic(Controller& controller, std::vector<Pose> poses, double duration_s,
                                     double latency_s = 0.2, double period_s = 0.1) {
  const ControllerConfig& c = controller.config();
  const std::size_t n = c.robots;
  const double dt = 0.01;
  controller.reset(poses, 0.0);
  std::vector<Unicycle> commands(n), applied(n);
  std::deque<std::pair<double, std::vector<Unicycle>>> pipe;  // (when it acts, commands)
  KinematicResult r;
  std::vector<Vec2> p(n);
  double last_bad_s = 0.0;
  const auto steps = static_cast<long>(duration_s / dt + 0.5);
  const long per_control = std::lround(period_s / dt);
  for (long k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) * dt;
    if (k % per_control == 0) {
      controller.step(t, poses, commands);
      pipe.emplace_back(t + latency_s, commands);
      for (std::size_t i = 0; i < n; ++i) p[i] = point_p(poses[i], c.offset_m);
      const double e = controller.formation_error(p);
      if (e > 0.05) last_bad_s = t;
    }
    while (!pipe.empty() && pipe.front().first <= t + 1e-9) {
      applied = pipe.front().second;
      pipe.pop_front();
    }
    for (std::size_t i = 0; i < n; ++i) {
      Pose& q = poses[i];
      const double v = std::clamp(applied[i].v, -c.v_max_m_s, c.v_max_m_s);
      const double w = std::clamp(applied[i].w, -c.w_max_rad_s, c.w_max_rad_s);
      q.x_m += v * std::cos(q.theta_rad + 0.5 * w * dt) * dt;
      q.y_m += v * std::sin(q.theta_rad + 0.5 * w * dt) * dt;
      q.theta_rad += w * dt;
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j)
        r.min_axle_distance_m = std::min(r.min_axle_distance_m, std::hypot(poses[i].x_m - poses[j].x_m, poses[i].y_m - poses[j].y_m));
      const Workspace& w = c.workspace;
      r.min_wall_clearance_m = std::min({r.min_wall_clearance_m, poses[i].x_m - w.x0_m - c.radius_m,
                                         w.x1_m - poses[i].x_m - c.radius_m, poses[i].y_m - w.y0_m - c.radius_m,
                                         w.y1_m - poses[i].y_m - c.radius_m});
    }
  }
  for (std::size_t i = 0; i < n; ++i) p[i] = point_p(poses[i], c.offset_m);
  r.final_error_m = controller.formation_error(p);
  r.converge_s = r.final_error_m <= 0.05 ? last_bad_s : -1.0;
  r.switches = controller.switches();
  r.final_poses = poses;
  return r;
}

// The example's starts, each moved by up to +-0.15 m and +-0.3 rad, redrawn until the body
// circles are 0.2 m apart and 0.1 m inside the walls.
inline std::vector<Pose> perturbed_starts(const Example& e, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> d(-0.15, 0.15), a(-0.3, 0.3);
  const std::size_t n = e.config.robots;
  const Workspace& w = e.config.workspace;
  for (;;) {
    std::vector<Pose> s(e.starts.begin(), e.starts.begin() + static_cast<long>(n));
    for (Pose& q : s) q = {q.x_m + d(rng), q.y_m + d(rng), q.theta_rad + a(rng)};
    bool ok = true;
    for (std::size_t i = 0; i < n && ok; ++i) {
      const double keep = e.config.radius_m + 0.1;
      ok = s[i].x_m - w.x0_m >= keep && w.x1_m - s[i].x_m >= keep && s[i].y_m - w.y0_m >= keep && w.y1_m - s[i].y_m >= keep;
      for (std::size_t j = i + 1; j < n && ok; ++j)
        ok = std::hypot(s[i].x_m - s[j].x_m, s[i].y_m - s[j].y_m) >= 2.0 * e.config.radius_m + 0.2;
    }
    if (ok) return s;
  }
}

}  // namespace sen3bot::formation::testing
