// Fuzz target: a candump log line gives a frame or an error that says why, never a crash;
// every frame it accepts is valid and is written back to a line that reads the same.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/hal/candump.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot;
  using namespace sen3bot::hal;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const Result<CandumpLine> line = parse_candump_line(text);
  if (!line) {
    if (line.error().message().empty()) __builtin_trap();
    return 0;
  }
  if (!line->frame.validate()) __builtin_trap();
  std::array<char, kMaxCandumpLine> out{};
  const std::size_t n = format_candump_line(*line, out);
  if (n == 0) __builtin_trap();
  const Result<CandumpLine> again = parse_candump_line(std::string_view(out.data(), n));
  if (!again || again->frame != line->frame || again->error_frame != line->error_frame ||
      again->interface_name() != line->interface_name() || again->unix_ns / 1000 != line->unix_ns / 1000)
    __builtin_trap();
  return 0;
}
