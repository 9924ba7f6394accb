// Fuzz target: any bytes as the formation link's two messages, the centre's formation command
// (what a robot reads) and a robot's visualization (what the centre reads), are decoded or
// refused, never a crash; what a robot accepts has a finite velocity and a hold in (0, 2] s,
// and what decodes encodes again and decodes to the same text. The bytes, and each decoded
// visualization's timestamp, are also read as ISO 8601 times: a time that reads is written
// back (at hundredths) and reads again to the same hundredth.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::vda5050;
  static DecodeScratch scratch;
  static FormationCommand command;
  static Visualization visualization;
  static std::array<char, 1 << 16> out;
  static std::array<char, 1 << 16> out2;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto time_round_trip = [](std::string_view stamp) {
    std::int64_t t = 0;
    if (!parse_iso8601(stamp, t)) return;
    // iso8601() writes times from 1970 (Unix nanoseconds in 64 bits end in 2262).
    if (t < 0) return;
    std::int64_t again = 0;
    if (!parse_iso8601(iso8601(t).view(), again) || again != t - t % 10'000'000) __builtin_trap();
  };
  time_round_trip(text);
  if (decode_formation(text, command, scratch).ok()) {
    if (!std::isfinite(command.v) || !std::isfinite(command.omega)) __builtin_trap();
    if (!(command.hold_s > 0 && command.hold_s <= kMaxFormationHoldS)) __builtin_trap();
    auto first = encode_formation(command, out);
    if (!first || !decode_formation(*first, command, scratch).ok()) __builtin_trap();
    auto second = encode_formation(command, out2);
    if (!second || *second != *first) __builtin_trap();
  }
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    const Decoded d = decode_visualization(text, v, visualization, scratch);
    if (!d && (d.error().error_type.empty() || d.error().description.empty())) __builtin_trap();
    // An empty timestamp decodes but is not written again (the encoder refuses it).
    if (d) time_round_trip(visualization.header.timestamp.view());
    if (d && !visualization.header.timestamp.empty()) {
      auto first = encode_visualization(visualization, v, out);
      if (!first || !decode_visualization(*first, v, visualization, scratch)) __builtin_trap();
      auto second = encode_visualization(visualization, v, out2);
      if (!second || *second != *first) __builtin_trap();
    }
  }
  return 0;
}
