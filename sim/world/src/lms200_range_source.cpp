#include "sen3bot/world/lms200_range_source.hpp"

#include <limits>

namespace sen3bot::world {

void WorldRangeSource::ranges(hal::Nanos t, const lms200::ScanGeometry& geometry, std::span<float> out_m) {
  if (advance_movers_) world_.set_time(static_cast<double>(t) * 1e-9);
  const lms200::SensorPose p = sensor_pose();
  world_.noisy_scan({p.x_m, p.y_m, p.theta_rad}, geometry.angle_min_rad, geometry.angle_increment_rad, geometry.count,
                    geometry.range_max_m, out_m);
  const auto limit = static_cast<float>(geometry.range_max_m);
  for (float& r : out_m) {
    if (r >= limit) r = std::numeric_limits<float>::infinity();
  }
}

}  // namespace sen3bot::world
