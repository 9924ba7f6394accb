// Fuzz target: any bytes as an order or instant actions, in either version, are accepted or
// refused with an errorType and a description, never a crash; an accepted order encodes and
// decodes back to the same text.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/vda5050/codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::vda5050;
  static DecodeScratch scratch;
  static Order order;
  static InstantActions actions;
  static std::array<char, 1 << 20> out;
  static std::array<char, 1 << 20> out2;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    const Decoded d = decode_order(text, v, order, scratch);
    if (!d && (d.error().error_type.empty() || d.error().description.empty())) __builtin_trap();
    if (d) {
      auto first = encode_order(order, v, out);
      if (!first) __builtin_trap();
      if (!decode_order(*first, v, order, scratch)) __builtin_trap();
      auto second = encode_order(order, v, out2);
      if (!second || *second != *first) __builtin_trap();
    }
    const Decoded a = decode_instant_actions(text, v, actions, scratch);
    if (!a && a.error().error_type.empty()) __builtin_trap();
    if (a && !encode_instant_actions(actions, v, out)) __builtin_trap();
  }
  return 0;
}
