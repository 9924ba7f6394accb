#pragma once
// The operator's QR tags: what a tag's code says and how it is checked.
//
// Payload (18 characters, all in QR's alphanumeric set, so the code is version 2 at error
// correction level H: 25 x 25 modules, big enough to read at 1 m with a 10 cm tag):
//
//   S3B1:F:000042:7C1D
//   |  | | |      +-- check: CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) of the 13
//   |  | | |          characters before it, as 4 upper-case hexadecimal digits
//   |  | | +-- operator id, 6 decimal digits, 000001..999999 (000000 is no operator)
//   |  | +-- side of the leg band: F (front, shown first) or B (back)
//   |  +-- format version (this firmware reads version 1)
//   +-- "S3B": a Sen3Bot tag; anything else is another QR code of the plant
//
// A code from elsewhere that happens to start with "S3B1:" still needs the right layout and a
// matching check (1 in 65536 by chance) before it is taken for a tag.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/cobot.hpp"

namespace sen3bot::cobot {

struct Tag {
  std::uint32_t operator_id = 0;  // 1..kMaxOperatorId
  msg::TagSide side = msg::TagSide::front;
};

inline constexpr std::uint32_t kMaxOperatorId = 999'999;
inline constexpr std::size_t kTagPayloadLength = 18;
inline constexpr char kTagFormatVersion = '1';

// Why a decoded QR code was not taken for a tag, most likely first.
enum class TagRefusal : std::uint8_t {
  foreign,          // not a Sen3Bot tag (no "S3B" at the start): another code of the plant
  unknown_version,  // a Sen3Bot tag of a format version this firmware does not read
  malformed,        // the right prefix, but the wrong length, separators or check digits
  bad_side,         // the side is neither F nor B
  bad_operator,     // the operator id is not 6 digits, or is 000000
  bad_check,        // everything in place but the check does not match (misread or forged)
};
inline constexpr std::size_t kTagRefusals = 6;
[[nodiscard]] const char* to_string(TagRefusal refusal) noexcept;

// The payload's characters; text() is the payload without a terminator.
struct TagPayload {
  std::array<char, kTagPayloadLength + 1> chars{};  // NUL-terminated
  [[nodiscard]] std::string_view text() const noexcept { return {chars.data(), kTagPayloadLength}; }
  [[nodiscard]] const char* c_str() const noexcept { return chars.data(); }
};

// The payload of a tag. Errc::invalid_argument when the operator id is 0 or above
// kMaxOperatorId.
[[nodiscard]] Result<TagPayload> encode_tag(const Tag& tag) noexcept;

// Reads a payload. On a refusal, returns it and leaves `out` as it was. No allocation.
[[nodiscard]] bool check_tag(std::string_view payload, Tag& out, TagRefusal& refusal) noexcept;

// As check_tag, with an error naming what is wrong (Errc::protocol; Errc::not_supported for an
// unknown format version).
[[nodiscard]] Result<Tag> parse_tag(std::string_view payload) noexcept;

// CRC-16/CCITT-FALSE of the text (the payload's check).
[[nodiscard]] std::uint16_t tag_check(std::string_view text) noexcept;

// "FRONT" or "BACK", as printed under a tag.
[[nodiscard]] constexpr const char* side_name(msg::TagSide side) noexcept {
  return side == msg::TagSide::front ? "FRONT" : "BACK";
}

}  // namespace sen3bot::cobot
