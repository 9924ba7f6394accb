#pragma once
// The devices' own types to the message vocabulary: pure conversions the device tasks apply to
// every scan and every SIP. A few assignments; nothing allocated.
#include "sen3bot/detector/detections.hpp"
#include "sen3bot/lms200/scan.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/p2os/types.hpp"

namespace sen3bot::firmware {

// LMS200 scan -> navigation scan. "Over maximum" (no echo) becomes range_max, which clears
// without marking; any other invalid value (dazzle, overflow, weak signal) becomes NaN, which
// navigation ignores: an unreadable beam must not clear an obstacle.
void to_nav_scan(const lms200::LaserScan& in, msg::ScanMessage& out) noexcept;
msg::Odometry to_nav_odometry(const p2os::BaseState& in) noexcept;
msg::BaseFlags to_base_flags(const p2os::BaseState& in) noexcept;
// A detector's boxes of one frame -> the people detections on the bus.
void to_person_detections(const detector::Detections& in, msg::PersonDetections& out) noexcept;

}  // namespace sen3bot::firmware
