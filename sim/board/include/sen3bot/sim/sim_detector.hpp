#pragma once
// The simulated remote person detector: it sees the world's true people through the robot's
// camera (the same calibration the fusion uses), draws a box around each as a detector would,
// with configurable pixel noise, misses, false positives and latency, and delivers each frame
// as a detection datagram (drivers/detector) on the simulated board's "detector" channel. The
// firmware reads it through the very gate and fusion it runs on the robot.
#include <array>
#include <cstdint>
#include <random>

#include "sen3bot/detector/protocol.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/mem/spsc_ring.hpp"
#include "sen3bot/nav/people.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::sim {

struct SimDetectorConfig {
  bool enabled = false;
  double rate_hz = 10.0;
  double latency_s = 0.1;             // from capture to the datagram's arrival
  double noise_px = 4.0;              // sigma on each box edge
  double miss_rate = 0.05;            // a visible person left out of a frame
  double false_positive_rate = 0.02;  // a frame with a box where nobody is
  double max_range_m = 8.0;           // farther people are not detected
  double laser_height_m = 0.3;        // the scan plane above the floor
  double person_height_m = 1.75;
  std::uint32_t source = 1;
  nav::CameraCalibration camera;
};

class SimDetector final : public hal::DatagramPort {
 public:
  SimDetector(const SimDetectorConfig& config, std::uint64_t seed);

  // A world step: captures a frame when one is due (people are the world's movers whose
  // `person` flag is set, the crowd's walkers among them), and releases the frames whose
  // latency has passed. Producer side.
  void step(hal::Nanos now_ns, std::int64_t unix_now_ns, const world::World& world, const nav::Pose2D& laser_pose) noexcept;
  // Consumer side (the firmware's detector task).
  Result<std::optional<std::size_t>> receive(std::span<std::uint8_t> out) override;

  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }

 private:
  struct Pending {
    hal::Nanos due_ns = 0;
    std::uint16_t size = 0;
    std::array<std::uint8_t, detector::kMaxDatagramBytes> bytes{};
  };
  // The box a person of width size_m at (forward, left) of the laser makes; false when not in view.
  bool box_for(double forward_m, double left_m, double size_m, detector::Box& box) noexcept;

  SimDetectorConfig config_;
  nav::CameraProjection camera_;
  std::mt19937_64 rng_;
  std::array<Pending, 16> delayed_{};  // captured, waiting out the latency (oldest first)
  std::size_t delayed_count_ = 0;
  mem::SpscRing<Pending, 16> ready_;
  hal::Nanos next_frame_ns_ = 0;
  std::uint32_t sequence_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace sen3bot::sim
