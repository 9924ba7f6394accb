#include "sen3bot/cobot/tag.hpp"

namespace sen3bot::cobot {

namespace {

// Where each field sits in "S3B1:F:000042:7C1D".
constexpr std::string_view kPrefix = "S3B";
constexpr std::size_t kVersionAt = 3;
constexpr std::size_t kSideAt = 5;
constexpr std::size_t kOperatorAt = 7;
constexpr std::size_t kOperatorDigits = 6;
constexpr std::size_t kCheckAt = 14;
constexpr std::size_t kCheckDigits = 4;
constexpr std::size_t kCheckedLength = kCheckAt - 1;  // the characters the check covers
constexpr char kSeparator = ':';
constexpr std::size_t kSeparatorsAt[] = {4, 6, 13};
constexpr char kHexDigits[] = "0123456789ABCDEF";

bool is_digit(char c) noexcept { return c >= '0' && c <= '9'; }

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;  // lower case too: the payload is in QR's alphanumeric set, upper case only
}

}  // namespace

const char* to_string(TagRefusal refusal) noexcept {
  switch (refusal) {
    case TagRefusal::foreign: return "foreign";
    case TagRefusal::unknown_version: return "unknown_version";
    case TagRefusal::malformed: return "malformed";
    case TagRefusal::bad_side: return "bad_side";
    case TagRefusal::bad_operator: return "bad_operator";
    case TagRefusal::bad_check: return "bad_check";
  }
  return "unknown";
}

std::uint16_t tag_check(std::string_view text) noexcept {
  std::uint16_t crc = 0xFFFF;
  for (const char c : text) {
    crc = static_cast<std::uint16_t>(crc ^ (static_cast<std::uint8_t>(c) << 8));
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000) != 0 ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021) : static_cast<std::uint16_t>(crc << 1);
    }
  }
  return crc;
}

Result<TagPayload> encode_tag(const Tag& tag) noexcept {
  if (tag.operator_id == 0 || tag.operator_id > kMaxOperatorId) {
    return Error::format(Errc::invalid_argument, "tag: operator id %u is outside 1..%u", tag.operator_id,
                         kMaxOperatorId);
  }
  TagPayload payload;
  char* p = payload.chars.data();
  for (std::size_t i = 0; i < kPrefix.size(); ++i) p[i] = kPrefix[i];
  p[kVersionAt] = kTagFormatVersion;
  for (const std::size_t at : kSeparatorsAt) p[at] = kSeparator;
  p[kSideAt] = tag.side == msg::TagSide::front ? 'F' : 'B';
  std::uint32_t id = tag.operator_id;
  for (std::size_t i = kOperatorDigits; i-- > 0;) {
    p[kOperatorAt + i] = static_cast<char>('0' + id % 10);
    id /= 10;
  }
  const std::uint16_t check = tag_check({p, kCheckedLength});
  for (std::size_t i = 0; i < kCheckDigits; ++i) {
    p[kCheckAt + i] = kHexDigits[(check >> (4 * (kCheckDigits - 1 - i))) & 0xF];
  }
  p[kTagPayloadLength] = '\0';
  return payload;
}

bool check_tag(std::string_view payload, Tag& out, TagRefusal& refusal) noexcept {
  if (payload.substr(0, kPrefix.size()) != kPrefix) {
    refusal = TagRefusal::foreign;
    return false;
  }
  if (payload.size() <= kVersionAt || payload[kVersionAt] != kTagFormatVersion) {
    // "S3B" alone, or a version this firmware does not know.
    refusal = payload.size() > kVersionAt && is_digit(payload[kVersionAt]) ? TagRefusal::unknown_version
                                                                           : TagRefusal::malformed;
    return false;
  }
  bool layout = payload.size() == kTagPayloadLength;
  for (const std::size_t at : kSeparatorsAt) layout = layout && payload[at] == kSeparator;
  std::uint16_t written_check = 0;
  for (std::size_t i = 0; layout && i < kCheckDigits; ++i) {
    const int digit = hex_value(payload[kCheckAt + i]);
    layout = digit >= 0;
    written_check = static_cast<std::uint16_t>((written_check << 4) | (digit & 0xF));
  }
  if (!layout) {
    refusal = TagRefusal::malformed;
    return false;
  }
  const char side = payload[kSideAt];
  if (side != 'F' && side != 'B') {
    refusal = TagRefusal::bad_side;
    return false;
  }
  std::uint32_t id = 0;
  for (std::size_t i = 0; i < kOperatorDigits; ++i) {
    const char c = payload[kOperatorAt + i];
    if (!is_digit(c)) {
      refusal = TagRefusal::bad_operator;
      return false;
    }
    id = id * 10 + static_cast<std::uint32_t>(c - '0');
  }
  if (id == 0) {
    refusal = TagRefusal::bad_operator;
    return false;
  }
  if (tag_check(payload.substr(0, kCheckedLength)) != written_check) {
    refusal = TagRefusal::bad_check;
    return false;
  }
  out.operator_id = id;
  out.side = side == 'F' ? msg::TagSide::front : msg::TagSide::back;
  return true;
}

Result<Tag> parse_tag(std::string_view payload) noexcept {
  Tag tag;
  TagRefusal refusal = TagRefusal::foreign;
  if (check_tag(payload, tag, refusal)) return tag;
  // Enough of the text to recognise it, without flooding a log with a long foreign payload.
  constexpr int kShown = 40;
  const int shown = payload.size() < static_cast<std::size_t>(kShown) ? static_cast<int>(payload.size()) : kShown;
  const char* more = payload.size() > static_cast<std::size_t>(kShown) ? "..." : "";
  switch (refusal) {
    case TagRefusal::foreign:
      return Error::format(Errc::protocol, "tag: '%.*s%s' is not a Sen3Bot tag (no S3B prefix)", shown, payload.data(),
                           more);
    case TagRefusal::unknown_version:
      return Error::format(Errc::not_supported, "tag: '%.*s%s' is tag format version %c; this firmware reads %c", shown,
                           payload.data(), more, payload[kVersionAt], kTagFormatVersion);
    case TagRefusal::malformed:
      return Error::format(Errc::protocol,
                           "tag: '%.*s%s' is not laid out as S3B1:F:000042:7C1D (%zu characters, upper-case hex "
                           "check)",
                           shown, payload.data(), more, kTagPayloadLength);
    case TagRefusal::bad_side:
      return Error::format(Errc::protocol, "tag: '%.*s': side '%c' is neither F nor B", shown, payload.data(),
                           payload[kSideAt]);
    case TagRefusal::bad_operator:
      return Error::format(Errc::protocol, "tag: '%.*s': operator id '%.*s' is not 000001..999999", shown,
                           payload.data(), static_cast<int>(kOperatorDigits), payload.data() + kOperatorAt);
    case TagRefusal::bad_check:
      return Error::format(Errc::protocol, "tag: '%.*s': check %.*s does not match %04X (misread or not a tag)", shown,
                           payload.data(), static_cast<int>(kCheckDigits), payload.data() + kCheckAt,
                           static_cast<unsigned>(tag_check(payload.substr(0, kCheckedLength))));
  }
  return Error(Errc::protocol, "tag: refused");
}

}  // namespace sen3bot::cobot
