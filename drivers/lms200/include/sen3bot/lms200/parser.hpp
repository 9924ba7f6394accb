#pragma once
// Telegram parser over a fixed byte ring. Bytes go in with push(); next() hands out CRC-checked
// telegrams and standalone ACK/NAK bytes. Nothing is trusted before the CRC: on a bad address,
// a LEN outside 1..814 or a CRC mismatch the parser advances one byte past the STX and scans
// again, so a real telegram that starts inside a false one is still found. No allocation.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {

enum class Side : std::uint8_t {
  from_device,  // replies: ADR = 0x80 | LMS address, LEN >= 2 (code + status)
  from_host,    // requests: ADR < 0x80, LEN >= 1
};

struct ParserStats {
  std::uint64_t frames = 0;
  std::uint64_t acks = 0;
  std::uint64_t naks = 0;
  std::uint64_t garbage_bytes = 0;   // bytes outside any telegram (not STX/ACK/NAK)
  std::uint64_t bad_headers = 0;     // STX followed by a wrong address or LEN out of range
  std::uint64_t crc_errors = 0;      // complete candidate telegrams whose CRC failed
  std::uint64_t dropped_partials = 0;  // incomplete telegrams abandoned by drop_partial()
  std::uint64_t overflow_bytes = 0;  // bytes refused by push() because the ring was full
};

class TelegramParser {
 public:
  // Two maximum-size telegrams fit, so a false header with a large LEN never blocks the
  // real telegram behind it.
  static constexpr std::size_t kCapacityBytes = 2048;

  enum class Kind : std::uint8_t { frame, ack, nak };
  struct Event {
    Kind kind = Kind::frame;
    FrameView frame;  // valid until the next call to next(), push() or reset()
  };

  // `lms_address`: which LMS to accept replies from (ignored for Side::from_host).
  explicit TelegramParser(Side side, std::uint8_t lms_address = 0) noexcept
      : side_(side), address_(lms_address) {}

  // Copies as many bytes as fit and returns that count (the rest counts as overflow only if
  // the caller drops it; call next() until false, then push the remainder).
  std::size_t push(std::span<const std::uint8_t> bytes) noexcept;
  [[nodiscard]] std::size_t free_space() const noexcept { return kCapacityBytes - size(); }
  [[nodiscard]] std::size_t size() const noexcept { return static_cast<std::size_t>(tail_ - head_); }

  // The next telegram or ACK/NAK; false when more bytes are needed.
  bool next(Event& out) noexcept;

  // True when next() returned false with an incomplete telegram at the head.
  [[nodiscard]] bool has_partial() const noexcept { return size() > 0 && at(0) == kStx; }
  // Abandons the incomplete telegram at the head (inter-byte gap or deadline passed):
  // advances one byte and rescans from there.
  void drop_partial() noexcept;
  // Forgets everything buffered (after a baud change, for example).
  void reset() noexcept { head_ = tail_ = 0; }

  void count_overflow(std::size_t bytes) noexcept { stats_.overflow_bytes += bytes; }
  [[nodiscard]] const ParserStats& stats() const noexcept { return stats_; }

 private:
  static constexpr std::size_t kMask = kCapacityBytes - 1;
  static_assert((kCapacityBytes & kMask) == 0, "power of two");
  static_assert(kCapacityBytes >= 2 * kMaxFrameBytes);

  [[nodiscard]] std::uint8_t at(std::size_t i) const noexcept { return ring_[(head_ + i) & kMask]; }
  void skip(std::size_t n) noexcept { head_ += n; }
  bool address_ok(std::uint8_t adr) const noexcept;

  Side side_;
  std::uint8_t address_;
  std::array<std::uint8_t, kCapacityBytes> ring_{};
  std::array<std::uint8_t, kMaxFrameBytes> frame_{};  // the telegram handed out, contiguous
  std::uint64_t head_ = 0;  // counters; ring position is counter & kMask
  std::uint64_t tail_ = 0;
  ParserStats stats_;
};

}  // namespace sen3bot::lms200
