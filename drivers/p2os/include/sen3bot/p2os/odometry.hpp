#pragma once
// SIP odometry: 15-bit x/y counters unwrapped with modular deltas (ARIA's scheme), heading
// integrated from THPOS deltas modulo 4096 (exact 2*pi/4096, not the rounded 0.00153).
#include <cstdint>
#include <numbers>

#include "sen3bot/geometry/geometry.hpp"
#include "sen3bot/p2os/codec.hpp"

namespace sen3bot::p2os {

// Conversion factors of a P3-DX with the SH (ARCOS) controller; see docs/p2os.md.
struct ConversionFactors {
  double dist_conv_mm_per_unit = 1.0;  // DistConvFactor: 1.0 on p3dx-sh, 0.485 on the old p3dx
  double vel_conv_mm_s_per_unit = 1.0;  // VelConvFactor
  double angle_conv_rad_per_unit = 2.0 * std::numbers::pi / 4096.0;  // THPOS unit
  double diff_conv_rad_per_mm = 0.0056;  // DiffConvFactor: omega = (R - L) / 2 * this
  double range_conv_mm_per_unit = 1.0;   // RangeConvFactor (sonar)
};

using Pose2 = geometry::Pose2D;

// Wraps an angle to (-pi, pi].
double wrap_angle_rad(double angle_rad) noexcept;

class Odometry {
 public:
  explicit Odometry(const ConversionFactors& factors = {}) noexcept : factors_(factors) {}

  // The first SIP after reset() seeds the pose from the raw counters (x/y sign-extended
  // from 15 bits); later SIPs add deltas.
  void update(const Sip& sip) noexcept;
  void reset() noexcept { seeded_ = false; }
  // A new session: the controller may have restarted its counters (each TCP session of a
  // simulator does). The next SIP becomes the counters' reference and the pose carries on
  // from where it was, so odometry never jumps; motion while the link was down is lost.
  void rebase() noexcept { rebase_ = seeded_; }

  [[nodiscard]] const Pose2& pose() const noexcept { return pose_; }
  [[nodiscard]] double distance_m() const noexcept { return distance_m_; }
  [[nodiscard]] bool seeded() const noexcept { return seeded_; }

  // Signed modular difference of two 15-bit counters, in (-0x4000, 0x4000].
  static std::int32_t position_delta(std::uint16_t now_raw, std::uint16_t last_raw) noexcept;
  // Signed difference of two headings in 4096ths, in [-2048, 2048).
  static std::int32_t theta_delta(std::int16_t now_raw, std::int16_t last_raw) noexcept;

 private:
  ConversionFactors factors_;
  Pose2 pose_;
  double theta_unwrapped_rad_ = 0;
  double distance_m_ = 0;
  std::uint16_t last_x_ = 0;
  std::uint16_t last_y_ = 0;
  std::int16_t last_theta_ = 0;
  bool seeded_ = false;
  bool rebase_ = false;
};

}  // namespace sen3bot::p2os
