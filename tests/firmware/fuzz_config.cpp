// Fuzz target: the configuration parser must turn any bytes into a configuration or an error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto result = sen3bot::firmware::parse_config(text, "fuzz.yaml");
  if (!result && result.error().message().empty()) __builtin_trap();  // every error says why
  return 0;
}
