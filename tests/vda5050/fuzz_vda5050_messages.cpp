// Fuzz target: any bytes as what the fleet's centre reads from the outside world (a vehicle's
// state and connection, a robot's people report, an advisory) are decoded or refused, never a
// crash; what decodes encodes again and decodes to the same text.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::vda5050;
  static DecodeScratch scratch;
  static State state;
  static Connection connection;
  static PeopleMessage people;
  static AdvisoryMessage advisory;
  static std::array<char, 1 << 20> out;
  static std::array<char, 1 << 20> out2;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    const Decoded s = decode_state(text, v, state, scratch);
    if (!s && s.error().error_type.empty()) __builtin_trap();
    const Decoded c = decode_connection(text, v, connection, scratch);
    if (!c && c.error().error_type.empty()) __builtin_trap();
    if (c && !encode_connection(connection, v, out)) __builtin_trap();
  }
  if (decode_people(text, people, scratch).ok()) {
    auto first = encode_people(people, out);
    if (!first || !decode_people(*first, people, scratch).ok()) __builtin_trap();
    auto second = encode_people(people, out2);
    if (!second || *second != *first) __builtin_trap();
  }
  if (decode_advisory(text, advisory, scratch).ok()) {
    auto first = encode_advisory(advisory, out);
    if (!first || !decode_advisory(*first, advisory, scratch).ok()) __builtin_trap();
    auto second = encode_advisory(advisory, out2);
    if (!second || *second != *first) __builtin_trap();
  }
  return 0;
}
