#include "sen3bot/sim/cobot/sim_camera.hpp"

#include <cmath>
#include <numbers>

namespace sen3bot::sim::cobot {

using ::sen3bot::cobot::SceneTag;

Result<std::unique_ptr<SimCamera>> SimCamera::create(const SimCameraConfig& config, std::uint64_t seed) {
  if (!(config.rate_hz > 0.0)) return Error(Errc::invalid_argument, "simulated camera: rate_hz must be positive");
  std::unique_ptr<SimCamera> camera(new SimCamera(config));
  const auto width = static_cast<std::uint32_t>(config.camera.width_px);
  const auto height = static_cast<std::uint32_t>(config.camera.height_px);
  Result<std::unique_ptr<camera::FramePool>> pool =
      camera::FramePool::create(camera::FramePool::kMinSlots + 1, width, height, camera::PixelFormat::gray8);
  if (!pool) return pool.error();
  camera->pool_ = std::move(*pool);
  if (Status s = camera->renderer_.init(config.camera, seed, config.scene); !s) return s.error();
  return camera;
}

bool SimCamera::step(hal::Nanos now_ns, const nav::Pose2D& laser, std::span<const TagWearer> wearers) {
  if (now_ns < next_ns_) return false;
  const auto period = static_cast<hal::Nanos>(1e9 / config_.rate_hz);
  next_ns_ = next_ns_ == 0 ? now_ns + period : next_ns_ + period;
  if (next_ns_ <= now_ns) next_ns_ = now_ns + period;

  tag_count_ = 0;
  const double c = std::cos(laser.theta_rad), s = std::sin(laser.theta_rad);
  for (const TagWearer& w : wearers) {
    for (int side = 0; side < 2 && tag_count_ < tags_.size(); ++side) {
      const double normal = w.facing_rad + (side == 0 ? 0.0 : std::numbers::pi);
      const double x = w.at.x_m + config_.body_radius_m * std::cos(normal);
      const double y = w.at.y_m + config_.body_radius_m * std::sin(normal);
      const double dx = x - laser.x_m, dy = y - laser.y_m;
      const double forward = c * dx + s * dy, left = -s * dx + c * dy;
      if (forward < 0.05) continue;
      // 0 when the tag's face points straight at the camera.
      const double to_camera = std::atan2(-dy, -dx);
      const double facing = nav::normalize_angle(normal - to_camera);
      if (std::fabs(facing) >= std::numbers::pi / 2) continue;  // its face is turned away: only the band's edge
      SceneTag& tag = tags_[tag_count_++];
      tag.forward_m = forward;
      tag.left_m = left;
      tag.up_m = config_.tag_height_m - config_.laser_height_m;
      tag.facing_rad = facing;
      tag.side_m = config_.tag_side_m;
      tag.tag.operator_id = w.operator_id;
      tag.tag.side = side == 0 ? msg::TagSide::front : msg::TagSide::back;
    }
  }
  // No tag in view, nothing for the reader: the frame is not drawn (a third of a run's time).
  if (tag_count_ == 0) return false;
  const int slot = pool_->begin_write();
  if (slot < 0) return false;
  const std::span<std::uint8_t> pixels = pool_->slot_pixels(slot);
  renderer_.render({tags_.data(), tag_count_}, pixels, pool_->width_px(), camera::PixelFormat::gray8);
  pool_->publish(slot, pool_->width_px(), pool_->height_px(), static_cast<std::uint32_t>(now_ns / 11111), now_ns, now_ns);
  ++rendered_;
  return true;
}

}  // namespace sen3bot::sim::cobot
