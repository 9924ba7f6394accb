// Fuzzes the map YAML, PGM and waypoint readers: the first byte picks the reader. A map read
// from an image also goes through the ellipse fitter of the supervisory planner.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/map_ellipses.hpp"
#include "sen3bot/nav/waypoints.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] % 3 == 2) {
    auto points = sen3bot::nav::parse_waypoints(text, "fuzz.txt");
    (void)points;
  } else if (data[0] % 3 == 0) {
    auto yaml = sen3bot::nav::parse_map_yaml(text, "fuzz.yaml");
    (void)yaml;
  } else {
    auto image = sen3bot::nav::parse_pgm(text, "fuzz.pgm");
    if (image.ok() && image->pixels.size() <= 4096) {
      sen3bot::nav::MapYaml y;
      y.resolution_m = 0.05;
      const sen3bot::nav::OccupancyMap map = sen3bot::nav::occupancy_from_image(*image, y);
      {
        sen3bot::nav::MapEllipsesConfig config;
        config.max_map_cells = 4096;
        config.max_map_rows = 4096;
        config.max_obstacle_cells = 4096;
        static sen3bot::mem::BudgetArena arena("fuzz", sen3bot::nav::MapEllipses::storage_bytes(config));
        static sen3bot::nav::MapEllipses ellipses;
        static const bool ready = ellipses.init(config, arena).ok();
        if (ready && ellipses.fit(map).ok()) {
          // Every ellipse holds its cells: finite, positive axes.
          for (const auto& e : ellipses.ellipses())
            if (!(e.semi_minor_m > 0.0 && e.semi_major_m >= e.semi_minor_m)) __builtin_trap();
        }
      }
    }
  }
  return 0;
}
