#include "sen3bot/sim/sim_detector.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::sim {

SimDetector::SimDetector(const SimDetectorConfig& config, std::uint64_t seed) : config_(config), rng_(seed ^ 0xD37EC70Full) {
  (void)camera_.set(config.camera);  // the firmware checks the same calibration and reports it
}

bool SimDetector::box_for(double forward_m, double left_m, double size_m, detector::Box& box) noexcept {
  double ul = 0, vt = 0, ur = 0, vb = 0;
  if (!camera_.project_point(forward_m, left_m + size_m / 2, config_.person_height_m - config_.laser_height_m, ul, vt) ||
      !camera_.project_point(forward_m, left_m - size_m / 2, -config_.laser_height_m, ur, vb))
    return false;
  double uc = 0, vc = 0;
  // The person counts as in view when the middle of their legs (in the laser's plane) is.
  if (!camera_.project(forward_m, left_m, uc, vc)) return false;
  std::normal_distribution<double> noise(0.0, config_.noise_px);
  const double w = camera_.width_px() - 1.0;
  const double h = camera_.height_px() - 1.0;
  box.u0 = static_cast<float>(std::clamp(ul + noise(rng_), 0.0, w));
  box.u1 = static_cast<float>(std::clamp(ur + noise(rng_), 0.0, w));
  box.v0 = static_cast<float>(std::clamp(vt + noise(rng_), 0.0, h));
  box.v1 = static_cast<float>(std::clamp(vb + noise(rng_), 0.0, h));
  box.confidence = 0.9f;
  box.class_id = 0;
  return box.u1 - box.u0 >= 2.0f && box.v1 - box.v0 >= 2.0f;
}

void SimDetector::step(hal::Nanos now_ns, std::int64_t unix_now_ns, const world::World& world,
                       const nav::Pose2D& laser_pose) noexcept {
  if (!config_.enabled) return;
  if (now_ns >= next_frame_ns_) {
    next_frame_ns_ = now_ns + static_cast<hal::Nanos>(1e9 / config_.rate_hz);
    detector::Datagram d;
    d.source = config_.source;
    d.sequence = ++sequence_;
    d.capture_unix_ns = unix_now_ns;
    d.width_px = static_cast<std::uint16_t>(camera_.width_px());
    d.height_px = static_cast<std::uint16_t>(camera_.height_px());
    std::uniform_real_distribution<double> chance(0.0, 1.0);
    const double c = std::cos(laser_pose.theta_rad);
    const double s = std::sin(laser_pose.theta_rad);
    for (std::size_t i = 0; i < world.mover_count() && d.count < detector::kMaxBoxes; ++i) {
      const world::MoverScript& mover = world.mover_script(i);
      if (!mover.person || !world.mover_visible(i)) continue;
      const double size_m = mover.size_m;
      const nav::Point2D p = world.mover_position(i);
      const double dx = p.x_m - laser_pose.x_m;
      const double dy = p.y_m - laser_pose.y_m;
      const double range = std::hypot(dx, dy);
      if (range > config_.max_range_m || range < 0.3) continue;
      // Hidden behind a wall or another mover: the first thing along the ray is nearer.
      if (world.cast_ray(laser_pose.x_m, laser_pose.y_m, std::atan2(dy, dx), range) < range - size_m / 2 - 0.05) continue;
      if (chance(rng_) < config_.miss_rate) continue;
      detector::Box box;
      if (box_for(c * dx + s * dy, -s * dx + c * dy, size_m, box)) d.boxes[d.count++] = box;
    }
    if (d.count < detector::kMaxBoxes && chance(rng_) < config_.false_positive_rate) {
      // A box somewhere nobody is: a plausible size, anywhere in the image.
      std::uniform_real_distribution<double> u(0.0, camera_.width_px() - 120.0);
      const float u0 = static_cast<float>(u(rng_));
      d.boxes[d.count++] = {u0, 40.0f, u0 + 100.0f, static_cast<float>(camera_.height_px() - 20), 0.6f, 0};
    }
    ++frames_;
    if (delayed_count_ == delayed_.size()) {
      ++dropped_;
    } else {
      Pending& slot = delayed_[delayed_count_++];
      slot.due_ns = now_ns + static_cast<hal::Nanos>(config_.latency_s * 1e9);
      slot.size = static_cast<std::uint16_t>(detector::encode(d, slot.bytes));
    }
  }
  // Release what is due, oldest first.
  std::size_t released = 0;
  while (released < delayed_count_ && delayed_[released].due_ns <= now_ns) {
    if (!ready_.try_push(delayed_[released])) ++dropped_;
    ++released;
  }
  if (released > 0) {
    std::move(delayed_.begin() + static_cast<std::ptrdiff_t>(released),
              delayed_.begin() + static_cast<std::ptrdiff_t>(delayed_count_), delayed_.begin());
    delayed_count_ -= released;
  }
}

Result<std::optional<std::size_t>> SimDetector::receive(std::span<std::uint8_t> out) {
  Pending p;
  if (!ready_.try_pop(p)) return std::optional<std::size_t>{};
  if (p.size > out.size()) return Error(Errc::capacity, "a detection datagram larger than the receive buffer was dropped");
  std::copy_n(p.bytes.begin(), p.size, out.begin());
  return std::optional<std::size_t>{p.size};
}

}  // namespace sen3bot::sim
