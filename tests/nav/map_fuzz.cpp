// Fuzzes the map YAML, PGM and waypoint readers: the first byte picks the reader.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/nav/map.hpp"
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
      (void)sen3bot::nav::occupancy_from_image(*image, y);
    }
  }
  return 0;
}
