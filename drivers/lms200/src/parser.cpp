#include "sen3bot/lms200/parser.hpp"

#include <algorithm>

namespace sen3bot::lms200 {

std::size_t TelegramParser::push(std::span<const std::uint8_t> bytes) noexcept {
  const std::size_t n = std::min(bytes.size(), free_space());
  for (std::size_t i = 0; i < n; ++i) ring_[(tail_ + i) & kMask] = bytes[i];
  tail_ += n;
  return n;
}

bool TelegramParser::address_ok(std::uint8_t adr) const noexcept {
  if (side_ == Side::from_host) return (adr & kReplyAddressFlag) == 0;
  return adr == (kReplyAddressFlag | address_);
}

bool TelegramParser::next(Event& out) noexcept {
  const std::uint16_t min_len = side_ == Side::from_device ? 2 : kMinLen;
  while (size() > 0) {
    const std::uint8_t first = at(0);
    if (first == kStx) {
      if (size() < 2) return false;
      if (!address_ok(at(1))) {
        ++stats_.bad_headers;
        skip(1);
        continue;
      }
      if (size() < kHeaderBytes) return false;
      const auto len = static_cast<std::uint16_t>(at(2) | (at(3) << 8));
      if (len < min_len || len > kMaxLen) {
        ++stats_.bad_headers;
        skip(1);
        continue;
      }
      const std::size_t total = len + kFrameOverheadBytes;
      if (size() < total) return false;
      for (std::size_t i = 0; i < total; ++i) frame_[i] = at(i);
      const std::uint16_t crc = crc16({frame_.data(), total - kCrcBytes});
      const auto sent = static_cast<std::uint16_t>(frame_[total - 2] | (frame_[total - 1] << 8));
      if (crc != sent) {
        ++stats_.crc_errors;
        skip(1);
        continue;
      }
      skip(total);
      ++stats_.frames;
      out.kind = Kind::frame;
      out.frame = FrameView{{frame_.data(), total}};
      return true;
    }
    skip(1);
    if (first == kAck) {
      ++stats_.acks;
      out.kind = Kind::ack;
      return true;
    }
    if (first == kNak) {
      ++stats_.naks;
      out.kind = Kind::nak;
      return true;
    }
    ++stats_.garbage_bytes;
  }
  return false;
}

void TelegramParser::drop_partial() noexcept {
  if (size() == 0) return;
  ++stats_.dropped_partials;
  skip(1);
}

}  // namespace sen3bot::lms200
