#pragma once
// RTP (RFC 3550): header parsing (§5.1, §5.3.1), extended sequence numbers and loss counting
// (Appendix A.1, A.3), a bounded reorder buffer for UDP, and a minimal RTCP receiver report
// (§6.4.2) that servers also take as keep-alive. Pure; the buffer allocates only when built.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera {

constexpr std::size_t kRtpFixedHeaderBytes = 12;
constexpr std::uint8_t kRtpVersion = 2;

struct RtpPacket {
  bool marker = false;
  std::uint8_t payload_type = 0;
  std::uint16_t sequence = 0;
  std::uint32_t timestamp = 0;
  std::uint32_t ssrc = 0;
  std::span<const std::uint8_t> payload;  // after CSRCs, extension and before padding
};

// Errc::protocol on: shorter than the header, V != 2, CSRC list or extension past the end,
// a padding count larger than the payload.
Result<RtpPacket> parse_rtp(std::span<const std::uint8_t> datagram);

// RFC 3550 Appendix A.1 source validation and sequence bookkeeping.
class SequenceTracker {
 public:
  static constexpr std::uint32_t kMaxDropout = 3000;
  static constexpr std::uint32_t kMaxMisorder = 100;
  static constexpr std::uint32_t kMinSequential = 2;

  enum class Verdict : std::uint8_t { accept, duplicate_or_late, probation, restart };

  // Classifies seq and, when accepted, returns its extended (cycle-counted) number.
  Verdict update(std::uint16_t seq, std::uint64_t& extended);
  void reset() { *this = SequenceTracker(); }

  [[nodiscard]] std::uint64_t received() const { return received_; }
  [[nodiscard]] std::uint64_t expected() const { return initialised_ ? max_extended() - base_extended_ + 1 : 0; }
  [[nodiscard]] std::uint64_t lost() const {
    const std::uint64_t e = expected();
    return e > received_ ? e - received_ : 0;
  }
  [[nodiscard]] std::uint64_t max_extended() const { return (std::uint64_t{cycles_} << 16) | max_seq_; }

 private:
  void init(std::uint16_t seq);

  bool initialised_ = false;
  std::uint16_t max_seq_ = 0;
  std::uint32_t cycles_ = 0;
  std::uint64_t base_extended_ = 0;
  std::uint32_t bad_seq_ = 0x10000 + 1;  // RTP_SEQ_MOD + 1: "no candidate"
  std::uint32_t probation_ = kMinSequential;
  std::uint64_t received_ = 0;
};

// Holds up to `depth` packets keyed by extended sequence number and releases them in order.
// A hole is skipped (counted lost) when the buffer is full; a packet at or behind what was
// released is late and dropped. Slots are allocated once, by the constructor.
class ReorderBuffer {
 public:
  ReorderBuffer(std::size_t depth, std::size_t max_packet_bytes);

  // ahead: the packet is a full window past what is held; pop(flush=true) and push again.
  enum class PushResult : std::uint8_t { stored, late, duplicate, too_big, ahead };
  PushResult push(std::uint64_t extended_seq, std::span<const std::uint8_t> packet);

  struct Released {
    std::span<const std::uint8_t> packet;  // valid until the next push or pop
    std::uint64_t extended_seq = 0;
    std::uint32_t lost_before = 0;         // packets skipped just before this one
  };
  // The next packet in order if it is here, or (when the buffer is full or `flush`) the
  // oldest held packet after a hole. False when nothing can be released yet.
  bool pop(Released& out, bool flush = false);

  [[nodiscard]] std::size_t held() const { return held_; }
  [[nodiscard]] std::uint64_t late_packets() const { return late_; }
  void clear();

 private:
  struct Slot {
    bool used = false;
    std::uint64_t seq = 0;
    std::size_t size = 0;
  };
  std::size_t depth_;
  std::size_t max_packet_bytes_;
  std::vector<Slot> slots_;
  std::vector<std::uint8_t> storage_;
  std::vector<std::uint8_t> out_;
  std::size_t held_ = 0;
  bool started_ = false;
  bool released_any_ = false;
  std::uint64_t next_seq_ = 0;
  std::uint64_t late_ = 0;
  std::uint64_t pending_gap_ = 0;
};

struct ReceiverReportInputs {
  std::uint32_t our_ssrc = 0;
  std::uint32_t source_ssrc = 0;
  bool have_source = false;          // false: an RR with no report block (legal, §6.4.2)
  std::uint8_t fraction_lost = 0;
  std::uint32_t cumulative_lost = 0;  // clamped to 24 bits
  std::uint32_t extended_highest_seq = 0;
  std::uint32_t jitter = 0;
};
// Writes a compound RR + SDES(CNAME) packet (§6.1 requires both) into out; returns its size,
// 0 if out is too small.
std::size_t build_receiver_report(const ReceiverReportInputs& in, std::span<std::uint8_t> out);

}  // namespace sen3bot::camera
