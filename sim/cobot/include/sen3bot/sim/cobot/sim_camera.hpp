#pragma once
// The simulated robot's camera for the collaborative mode: at its frame rate it renders what
// the camera sees of the operators' leg-band tags (perspective from where they stand and which
// way they face, blur, noise; cobot/tag_scene.hpp) into a frame pool that the firmware's QR
// reader takes its frames from, as it takes them from the RTSP client's pool on the robot.
#include <cstdint>
#include <memory>
#include <span>

#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/sim/cobot/tag_scene.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/people.hpp"

namespace sen3bot::sim::cobot {

struct SimCameraConfig {
  double rate_hz = 5.0;
  double tag_side_m = 0.10;
  double tag_height_m = 0.35;    // the leg band, above the floor
  double laser_height_m = 0.3;   // the scan plane, above the floor
  double body_radius_m = 0.12;   // the leg's front and back surfaces, from the person's centre
  nav::CameraCalibration camera;
  ::sen3bot::cobot::SceneOptions scene;
};

// A person wearing tags: where, which way their front faces (map frame), whose tags.
struct TagWearer {
  nav::Point2D at;
  double facing_rad = 0.0;
  std::uint32_t operator_id = 0;
};

class SimCamera {
 public:
  static Result<std::unique_ptr<SimCamera>> create(const SimCameraConfig& config, std::uint64_t seed);

  [[nodiscard]] camera::FramePool& frames() noexcept { return *pool_; }
  // Renders and publishes a frame when one is due at now_ns; `laser` is the laser's true pose.
  // A frame with no tag facing the camera is skipped: the tag reader would find nothing in it.
  // Returns whether a frame was published.
  bool step(hal::Nanos now_ns, const nav::Pose2D& laser, std::span<const TagWearer> wearers);
  [[nodiscard]] std::uint64_t frames_rendered() const noexcept { return rendered_; }
  // The tags of the newest frame, as drawn (for tests and reports).
  [[nodiscard]] std::span<const ::sen3bot::cobot::SceneTag> last_tags() const noexcept {
    return {tags_.data(), tag_count_};
  }

 private:
  explicit SimCamera(const SimCameraConfig& config) : config_(config) {}
  SimCameraConfig config_;
  std::unique_ptr<camera::FramePool> pool_;
  ::sen3bot::cobot::TagSceneRenderer renderer_;
  std::array<::sen3bot::cobot::SceneTag, 8> tags_{};
  std::size_t tag_count_ = 0;
  hal::Nanos next_ns_ = 0;
  std::uint64_t rendered_ = 0;
};

}  // namespace sen3bot::sim::cobot
