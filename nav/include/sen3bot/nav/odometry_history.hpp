#pragma once
// The last second or so of wheel odometry, to look up where the robot was when a scan was
// taken. The LMS200 at 38400 baud needs ~0.19 s to send a 361-beam scan, so a scan is 0.2-0.3 s
// old when the navigation tasks read it: at 0.5 m/s that is 10-15 cm of travel, which, if the
// scan were placed at the newest pose, would shift every laser point by as much (ROS looks up
// the transform at the scan's stamp for the same reason). Fixed capacity, no allocation.
#include <array>
#include <cstddef>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/scan.hpp"

namespace sen3bot::nav {

class OdometryHistory {
 public:
  static constexpr std::size_t kCapacity = 64;  // 6.4 s of 10 Hz odometry
  // Past the newest sample, poses are extrapolated with its velocities up to this long.
  static constexpr double kMaxExtrapolationS = 0.25;

  // Samples older than (or as old as) the newest are ignored.
  void push(const Odometry& odom) noexcept {
    if (!odom.valid) return;
    if (count_ > 0 && odom.stamp_ns <= newest().stamp_ns) return;
    samples_[(head_ + count_) % kCapacity] = odom;
    if (count_ < kCapacity) {
      ++count_;
    } else {
      head_ = (head_ + 1) % kCapacity;
    }
  }
  void clear() noexcept { count_ = 0; }
  [[nodiscard]] std::size_t size() const noexcept { return count_; }

  // The odometry pose at time t: interpolated between the samples around it, or extrapolated
  // a little past the newest. False when t is older than every sample or too far ahead.
  bool pose_at(hal::Nanos t_ns, Pose2D& out) const noexcept {
    if (count_ == 0) return false;
    const Odometry& last = newest();
    if (t_ns >= last.stamp_ns) {
      const double dt = static_cast<double>(t_ns - last.stamp_ns) * 1e-9;
      if (dt > kMaxExtrapolationS) return false;
      const double th = last.theta_rad + 0.5 * last.w_rad_s * dt;
      out = {last.x_m + last.v_m_s * dt * std::cos(th), last.y_m + last.v_m_s * dt * std::sin(th),
             normalize_angle(last.theta_rad + last.w_rad_s * dt)};
      return true;
    }
    for (std::size_t k = count_ - 1; k > 0; --k) {
      const Odometry& a = at(k - 1);
      const Odometry& b = at(k);
      if (t_ns < a.stamp_ns) continue;
      const double f = static_cast<double>(t_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
      out = {a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m),
             normalize_angle(a.theta_rad + f * normalize_angle(b.theta_rad - a.theta_rad))};
      return true;
    }
    return false;
  }

 private:
  [[nodiscard]] const Odometry& at(std::size_t k) const noexcept { return samples_[(head_ + k) % kCapacity]; }
  [[nodiscard]] const Odometry& newest() const noexcept { return at(count_ - 1); }

  std::array<Odometry, kCapacity> samples_{};
  std::size_t head_ = 0;
  std::size_t count_ = 0;
};

}  // namespace sen3bot::nav
