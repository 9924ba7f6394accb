#pragma once
// Plain geometry values carried by the bus messages: points and poses in the map frame and the
// laser's mount on the robot, from the one geometry kit (lib/geometry).
#include "sen3bot/geometry/geometry.hpp"

namespace sen3bot::msg {

using geometry::compose;
using geometry::normalize_angle;
using geometry::Point2D;
using geometry::Pose2D;
using geometry::SensorMount;

}  // namespace sen3bot::msg
