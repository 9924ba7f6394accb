#include "sen3bot/camera/rtp.hpp"

#include <cstring>

namespace sen3bot::camera {
namespace {

std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
void put16(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}
void put32(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}
constexpr std::uint32_t kSeqMod = 1u << 16;

}  // namespace

Result<RtpPacket> parse_rtp(std::span<const std::uint8_t> d) {
  if (d.size() < kRtpFixedHeaderBytes) return Error(Errc::protocol, "RTP packet shorter than its header");
  if ((d[0] >> 6) != kRtpVersion) return Error(Errc::protocol, "RTP version is not 2");
  const bool padding = (d[0] & 0x20) != 0;
  const bool extension = (d[0] & 0x10) != 0;
  const std::size_t csrc_count = d[0] & 0x0F;
  RtpPacket p;
  p.marker = (d[1] & 0x80) != 0;
  p.payload_type = d[1] & 0x7F;
  p.sequence = be16(&d[2]);
  p.timestamp = be32(&d[4]);
  p.ssrc = be32(&d[8]);
  std::size_t offset = kRtpFixedHeaderBytes + 4 * csrc_count;
  if (offset > d.size()) return Error(Errc::protocol, "RTP CSRC list past the end");
  if (extension) {
    if (offset + 4 > d.size()) return Error(Errc::protocol, "RTP extension header past the end");
    // §5.3.1: length in 32-bit words, not counting the 4-byte extension header.
    offset += 4 + 4 * std::size_t{be16(&d[offset + 2])};
    if (offset > d.size()) return Error(Errc::protocol, "RTP extension past the end");
  }
  std::size_t end = d.size();
  if (padding) {
    const std::size_t pad = d[d.size() - 1];
    if (pad == 0 || pad > end - offset) return Error(Errc::protocol, "RTP padding larger than the payload");
    end -= pad;
  }
  p.payload = d.subspan(offset, end - offset);
  return p;
}

void SequenceTracker::init(std::uint16_t seq) {
  initialised_ = true;
  max_seq_ = seq;
  cycles_ = 0;
  base_extended_ = seq;
  bad_seq_ = kSeqMod + 1;
  received_ = 0;
}

SequenceTracker::Verdict SequenceTracker::update(std::uint16_t seq, std::uint64_t& extended) {
  if (!initialised_) {
    // Probation: MIN_SEQUENTIAL in a row before the source counts as valid. We accept the
    // first packet at once (the server was chosen by us), but remember the base.
    init(seq);
    probation_ = 0;
    ++received_;
    extended = max_extended();
    return Verdict::accept;
  }
  const std::uint16_t udelta = static_cast<std::uint16_t>(seq - max_seq_);
  if (udelta == 0) return Verdict::duplicate_or_late;
  if (udelta < kMaxDropout) {
    if (seq < max_seq_) ++cycles_;  // wrapped
    max_seq_ = seq;
    ++received_;
    extended = max_extended();
    return Verdict::accept;
  }
  if (udelta <= kSeqMod - kMaxMisorder) {
    // A very large jump: the sender restarted, or this is a stray. Two in a row = restart.
    if (seq == bad_seq_) {
      const std::uint64_t lost_so_far = lost();
      init(seq);
      (void)lost_so_far;
      ++received_;
      extended = max_extended();
      return Verdict::restart;
    }
    bad_seq_ = (std::uint32_t{seq} + 1) & (kSeqMod - 1);
    return Verdict::probation;
  }
  // Misordered within MAX_MISORDER: an old packet. Its extended number is in this or the
  // previous cycle.
  std::uint64_t candidate = (std::uint64_t{cycles_} << 16) | seq;
  if (seq > max_seq_ && cycles_ > 0) candidate = (std::uint64_t{cycles_ - 1} << 16) | seq;
  if (candidate < base_extended_) return Verdict::duplicate_or_late;
  ++received_;
  extended = candidate;
  return Verdict::accept;
}

ReorderBuffer::ReorderBuffer(std::size_t depth, std::size_t max_packet_bytes)
    : depth_(depth == 0 ? 1 : depth),
      max_packet_bytes_(max_packet_bytes),
      slots_(depth_),
      storage_(depth_ * max_packet_bytes),
      out_(max_packet_bytes) {}

void ReorderBuffer::clear() {
  for (Slot& s : slots_) s.used = false;
  held_ = 0;
  started_ = false;
  released_any_ = false;
  pending_gap_ = 0;
}

ReorderBuffer::PushResult ReorderBuffer::push(std::uint64_t seq, std::span<const std::uint8_t> packet) {
  if (packet.size() > max_packet_bytes_) return PushResult::too_big;
  if (started_ && seq < next_seq_ && !released_any_ && next_seq_ - seq < depth_ && held_ < depth_) {
    // Nothing released yet: the first packet to arrive need not be the first one sent.
    bool fits = true;
    for (const Slot& slot : slots_) fits = fits && (!slot.used || slot.seq < seq + depth_);
    if (fits) next_seq_ = seq;
  }
  if (started_ && seq < next_seq_) {
    ++late_;
    return PushResult::late;
  }
  if (!started_) {
    started_ = true;
    next_seq_ = seq;
  }
  if (seq >= next_seq_ + depth_) {
    // Beyond the window: the caller must release what is held first (pop with flush).
    if (held_ > 0) return PushResult::ahead;
    pending_gap_ += seq - next_seq_;
    next_seq_ = seq;
  }
  const std::size_t index = static_cast<std::size_t>(seq % depth_);
  Slot& slot = slots_[index];
  if (slot.used) {
    return PushResult::duplicate;  // within the window a used slot holds this very number
  }
  slot.used = true;
  slot.seq = seq;
  slot.size = packet.size();
  std::memcpy(storage_.data() + index * max_packet_bytes_, packet.data(), packet.size());
  ++held_;
  return PushResult::stored;
}

bool ReorderBuffer::pop(Released& out, bool flush) {
  if (held_ == 0) return false;
  const bool full = held_ >= depth_;
  // The in-order packet?
  {
    const std::size_t index = static_cast<std::size_t>(next_seq_ % depth_);
    Slot& slot = slots_[index];
    if (slot.used && slot.seq == next_seq_) {
      std::memcpy(out_.data(), storage_.data() + index * max_packet_bytes_, slot.size);
      out.packet = std::span<const std::uint8_t>(out_.data(), slot.size);
      out.extended_seq = slot.seq;
      out.lost_before = static_cast<std::uint32_t>(pending_gap_ > 0xFFFFFFFFu ? 0xFFFFFFFFu : pending_gap_);
      pending_gap_ = 0;
      slot.used = false;
      --held_;
      ++next_seq_;
      released_any_ = true;
      return true;
    }
  }
  if (!full && !flush) return false;
  // Skip the hole: the oldest packet held is next.
  const Slot* oldest = nullptr;
  std::size_t oldest_index = 0;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].used && (oldest == nullptr || slots_[i].seq < oldest->seq)) {
      oldest = &slots_[i];
      oldest_index = i;
    }
  }
  if (oldest == nullptr) return false;
  Slot& slot = slots_[oldest_index];
  std::memcpy(out_.data(), storage_.data() + oldest_index * max_packet_bytes_, slot.size);
  out.packet = std::span<const std::uint8_t>(out_.data(), slot.size);
  out.extended_seq = slot.seq;
  const std::uint64_t gap = slot.seq - next_seq_ + pending_gap_;
  pending_gap_ = 0;
  out.lost_before = gap > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<std::uint32_t>(gap);
  next_seq_ = slot.seq + 1;
  released_any_ = true;
  slot.used = false;
  --held_;
  return true;
}

std::size_t build_receiver_report(const ReceiverReportInputs& in, std::span<std::uint8_t> out) {
  constexpr std::uint8_t kPtReceiverReport = 201;  // §6.4.2
  constexpr std::uint8_t kPtSdes = 202;            // §6.5
  constexpr std::uint8_t kSdesCname = 1;
  constexpr char kCname[] = "sen3bot";
  const std::size_t rr_bytes = 8 + (in.have_source ? 24 : 0);
  const std::size_t cname_len = sizeof(kCname) - 1;
  // SDES: header 4, SSRC 4, item type+len 2 + text, END 1, padded to 32 bits.
  const std::size_t sdes_raw = 4 + 4 + 2 + cname_len + 1;
  const std::size_t sdes_bytes = (sdes_raw + 3) / 4 * 4;
  if (out.size() < rr_bytes + sdes_bytes) return 0;
  std::memset(out.data(), 0, rr_bytes + sdes_bytes);
  std::uint8_t* p = out.data();
  p[0] = static_cast<std::uint8_t>(0x80 | (in.have_source ? 1 : 0));
  p[1] = kPtReceiverReport;
  put16(p + 2, static_cast<std::uint32_t>(rr_bytes / 4 - 1));
  put32(p + 4, in.our_ssrc);
  if (in.have_source) {
    put32(p + 8, in.source_ssrc);
    const std::uint32_t lost = in.cumulative_lost > 0x7FFFFF ? 0x7FFFFF : in.cumulative_lost;
    put32(p + 12, (std::uint32_t{in.fraction_lost} << 24) | lost);
    put32(p + 16, in.extended_highest_seq);
    put32(p + 20, in.jitter);
    // LSR and DLSR stay 0: we do not track sender reports.
  }
  std::uint8_t* s = p + rr_bytes;
  s[0] = 0x81;  // V=2, one chunk
  s[1] = kPtSdes;
  put16(s + 2, static_cast<std::uint32_t>(sdes_bytes / 4 - 1));
  put32(s + 4, in.our_ssrc);
  s[8] = kSdesCname;
  s[9] = static_cast<std::uint8_t>(cname_len);
  std::memcpy(s + 10, kCname, cname_len);
  return rr_bytes + sdes_bytes;
}

}  // namespace sen3bot::camera
