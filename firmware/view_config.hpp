#pragma once
// The live view's configuration (the `view` section; docs/view.md), apart from its task so the
// configuration reader needs no more than this.
#include <array>
#include <cstdint>
#include <string_view>

#include "sen3bot/view/server.hpp"

namespace sen3bot::firmware {

// The channels, in advertised order.
enum class ViewChannel : std::uint8_t {
  map, global_costmap, local_costmap, scan, tf, plan, safe_path, driven_path, dwa, people, camera, stats, mission,
};
inline constexpr std::size_t kViewChannels = 13;
std::string_view topic_of(ViewChannel channel) noexcept;
// The channel's key under view.channels: map, global_costmap, ..., mission.
std::string_view channel_key(ViewChannel channel) noexcept;

struct ViewTaskConfig {
  view::ServerConfig server;
  // Seconds between messages per channel, in ViewChannel order; 0 turns a channel off.
  std::array<double, kViewChannels> period_s = {5.0, 2.0, 0.5, 0.2, 0.1, 1.0, 2.0, 1.0, 0.2, 0.2, 1.0, 1.0, 0.5};
  std::uint32_t camera_max_width_px = 320;
  int camera_quality = 60;
  double driven_step_m = 0.1;  // one pose of /path/driven per this much travel
};

}  // namespace sen3bot::firmware
