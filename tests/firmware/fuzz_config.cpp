// Fuzz target: the configuration parsers must turn any bytes into a configuration or an error:
// the firmware's (as the robot reads a file, and as the simulator does, leaving it the `sim`
// section) and the simulated board's reader of that section.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config.hpp"
#include "sen3bot/sim/sim_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto robot = sen3bot::firmware::parse_config(text, "fuzz.yaml");
  if (!robot && robot.error().message().empty()) __builtin_trap();  // every error says why
  const std::string_view sections[] = {sen3bot::sim::kSimSection};
  auto simulated = sen3bot::firmware::parse_config(text, "fuzz.yaml", sections);
  if (!simulated && simulated.error().message().empty()) __builtin_trap();
  auto world = sen3bot::sim::parse_sim_config(text, "fuzz.yaml", {});
  if (!world && world.error().message().empty()) __builtin_trap();
  return 0;
}
