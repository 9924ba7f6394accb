#include <algorithm>
#include <cstring>

#include "sen3bot/camera/depacketizer.hpp"

namespace sen3bot::camera {
namespace {

constexpr std::uint8_t kStartCode[4] = {0, 0, 0, 1};  // H.264 Annex B
constexpr std::size_t kMaxParameterSetNalBytes = 1024;

}  // namespace

H264Depacketizer::H264Depacketizer(std::size_t max_access_unit_bytes)
    : au_(max_access_unit_bytes),
      out_(max_access_unit_bytes + 2 * (kMaxParameterSetNalBytes + sizeof kStartCode)),
      sps_(kMaxParameterSetNalBytes),
      pps_(kMaxParameterSetNalBytes) {}

void H264Depacketizer::set_parameter_sets(const std::vector<std::vector<std::uint8_t>>& nals) {
  for (const auto& nal : nals) {
    if (nal.empty() || nal.size() > kMaxParameterSetNalBytes) continue;
    const std::uint8_t type = nal[0] & 0x1F;
    if (type == kNalSps) {
      std::memcpy(sps_.data(), nal.data(), nal.size());
      sps_size_ = nal.size();
    } else if (type == kNalPps) {
      std::memcpy(pps_.data(), nal.data(), nal.size());
      pps_size_ = nal.size();
    }
  }
}

void H264Depacketizer::reset() {
  discard_au();
  have_idr_ = false;
}

void H264Depacketizer::discard_au() {
  au_size_ = 0;
  au_open_ = false;
  au_damaged_ = false;
  au_has_idr_ = false;
  au_has_sps_ = false;
  au_overflow_ = false;
  fu_open_ = false;
}

void H264Depacketizer::append_nal(std::span<const std::uint8_t> nal) {
  if (nal.empty()) return;
  if (au_size_ + sizeof kStartCode + nal.size() > au_.size()) {
    au_overflow_ = true;
    return;
  }
  std::memcpy(au_.data() + au_size_, kStartCode, sizeof kStartCode);
  std::memcpy(au_.data() + au_size_ + sizeof kStartCode, nal.data(), nal.size());
  au_size_ += sizeof kStartCode + nal.size();
  const std::uint8_t type = nal[0] & 0x1F;
  if (type == kNalIdrSlice) au_has_idr_ = true;
  // In-band parameter sets replace those from SDP.
  if ((type == kNalSps || type == kNalPps) && nal.size() <= kMaxParameterSetNalBytes) {
    if (type == kNalSps) {
      au_has_sps_ = true;
      std::memcpy(sps_.data(), nal.data(), nal.size());
      sps_size_ = nal.size();
    } else {
      std::memcpy(pps_.data(), nal.data(), nal.size());
      pps_size_ = nal.size();
    }
  }
}

void H264Depacketizer::emit(EncodedFrameSink& sink) {
  if (fu_open_) au_damaged_ = true;  // a fragmented NAL never got its end
  if (au_overflow_) {
    ++stats_.frames_dropped_oversize;
    have_idr_ = false;
    discard_au();
    return;
  }
  if (au_size_ == 0) {
    discard_au();
    return;
  }
  if (au_damaged_) {
    ++stats_.frames_dropped_damaged;
    have_idr_ = false;
    discard_au();
    return;
  }
  if (au_has_idr_) have_idr_ = true;
  if (!have_idr_) {
    // Without the IDR the decoder outputs nothing or garbage (brief §3.5); wait for one.
    ++stats_.frames_dropped_no_idr;
    discard_au();
    return;
  }
  EncodedFrame frame;
  frame.codec = VideoCodec::h264;
  frame.rtp_timestamp = au_timestamp_;
  frame.keyframe = au_has_idr_;
  frame.last_packet_ns = last_arrival_ns_;
  if (au_has_idr_ && !au_has_sps_ && sps_size_ > 0 && pps_size_ > 0) {
    std::size_t n = 0;
    for (const auto& [data, size] : {std::pair{sps_.data(), sps_size_}, std::pair{pps_.data(), pps_size_}}) {
      std::memcpy(out_.data() + n, kStartCode, sizeof kStartCode);
      std::memcpy(out_.data() + n + sizeof kStartCode, data, size);
      n += sizeof kStartCode + size;
    }
    std::memcpy(out_.data() + n, au_.data(), au_size_);
    frame.data = std::span<const std::uint8_t>(out_.data(), n + au_size_);
  } else {
    frame.data = std::span<const std::uint8_t>(au_.data(), au_size_);
  }
  ++stats_.frames_emitted;
  sink.on_frame(frame);
  discard_au();
}

void H264Depacketizer::push(const RtpPacket& packet, bool loss_before, Nanos arrival_ns, EncodedFrameSink& sink) {
  ++stats_.packets;
  if (loss_before) {
    if (au_open_) au_damaged_ = true;
    fu_open_ = false;
    have_idr_ = false;
  }
  // An AU also ends when the timestamp changes: some cameras never set the marker or set it
  // on the wrong packet (brief §2.3).
  if (au_open_ && packet.timestamp != au_timestamp_) emit(sink);
  const auto p = packet.payload;
  if (p.empty()) {
    ++stats_.malformed_packets;
  } else {
    if (!au_open_) {
      au_open_ = true;
      au_timestamp_ = packet.timestamp;
    }
    last_arrival_ns_ = arrival_ns;
    const std::uint8_t type = p[0] & 0x1F;
    if (type >= 1 && type <= 23) {
      fu_open_ = false;
      append_nal(p);
    } else if (type == kNalStapA) {
      std::size_t i = 1;
      while (i + 2 <= p.size()) {
        const std::size_t n = (std::size_t{p[i]} << 8) | p[i + 1];
        if (n == 0 || i + 2 + n > p.size()) {
          ++stats_.malformed_packets;
          break;
        }
        append_nal(p.subspan(i + 2, n));
        i += 2 + n;
      }
    } else if (type == kNalFuA) {
      if (p.size() < 3) {
        ++stats_.malformed_packets;
      } else {
        const bool start = (p[1] & 0x80) != 0;
        const bool end = (p[1] & 0x40) != 0;  // the reserved bit 0x20 is ignored (HeroSpeed sets it)
        const std::uint8_t header = static_cast<std::uint8_t>((p[0] & 0xE0) | (p[1] & 0x1F));
        if (start) {
          if (fu_open_) au_damaged_ = true;  // the previous fragment never ended
          if (au_size_ + sizeof kStartCode + 1 + (p.size() - 2) > au_.size()) {
            au_overflow_ = true;
          } else {
            fu_start_ = au_size_;
            std::memcpy(au_.data() + au_size_, kStartCode, sizeof kStartCode);
            au_[au_size_ + sizeof kStartCode] = header;
            std::memcpy(au_.data() + au_size_ + sizeof kStartCode + 1, p.data() + 2, p.size() - 2);
            au_size_ += sizeof kStartCode + 1 + (p.size() - 2);
            fu_open_ = true;
          }
        } else if (!fu_open_) {
          ++stats_.fragments_dropped;  // joined mid-NAL or lost the start
        } else if (au_size_ + (p.size() - 2) > au_.size()) {
          au_overflow_ = true;
          fu_open_ = false;
        } else {
          std::memcpy(au_.data() + au_size_, p.data() + 2, p.size() - 2);
          au_size_ += p.size() - 2;
        }
        if (end && fu_open_) {
          // A whole NAL (also when S and E are both set, which real cameras send).
          fu_open_ = false;
          const std::size_t nal_offset = fu_start_ + sizeof kStartCode;
          const std::size_t nal_size = au_size_ - nal_offset;
          const std::uint8_t nal_type = au_[nal_offset] & 0x1F;
          if (nal_type == kNalIdrSlice) au_has_idr_ = true;
          if ((nal_type == kNalSps || nal_type == kNalPps) && nal_size <= kMaxParameterSetNalBytes) {
            if (nal_type == kNalSps) {
              au_has_sps_ = true;
              std::memcpy(sps_.data(), au_.data() + nal_offset, nal_size);
              sps_size_ = nal_size;
            } else {
              std::memcpy(pps_.data(), au_.data() + nal_offset, nal_size);
              pps_size_ = nal_size;
            }
          }
        }
      }
    } else {
      ++stats_.unsupported_packets;  // STAP-B, MTAP16/24, FU-B: interleaved mode only
    }
  }
  if (packet.marker && au_open_) emit(sink);
}

}  // namespace sen3bot::camera
