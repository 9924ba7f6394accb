#pragma once
// Laser and odometry inputs of the navigation cores: the bus vocabulary's scan and odometry
// messages under their navigation names.
#include "sen3bot/msg/base.hpp"
#include "sen3bot/msg/laser.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::nav {

using msg::Odometry;
using msg::ScanMessage;
using msg::ScanView;

}  // namespace sen3bot::nav
