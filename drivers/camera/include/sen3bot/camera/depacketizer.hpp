#pragma once
// RTP payload depacketizers: H.264 (RFC 6184, packetization mode 1) into Annex-B access
// units, and JPEG (RFC 2435) into complete JFIF images. Both write into a buffer sized once
// at construction and never allocate per packet. Completed frames go to a sink.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "sen3bot/camera/rtp.hpp"
#include "sen3bot/camera/sdp.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::camera {

using hal::Nanos;

struct EncodedFrame {
  VideoCodec codec = VideoCodec::unknown;
  std::span<const std::uint8_t> data;  // Annex-B AU or a JFIF image; valid during the call
  std::uint32_t rtp_timestamp = 0;
  bool keyframe = false;               // H.264: contains an IDR slice; JPEG: always
  Nanos last_packet_ns = 0;            // arrival of the packet that completed it
};

class EncodedFrameSink {
 public:
  virtual ~EncodedFrameSink() = default;
  virtual void on_frame(const EncodedFrame& frame) = 0;
};

struct DepacketizerStats {
  std::uint64_t packets = 0;
  std::uint64_t frames_emitted = 0;
  std::uint64_t frames_dropped_damaged = 0;   // a loss inside the frame
  std::uint64_t frames_dropped_no_idr = 0;    // H.264 waiting for an IDR after start or loss
  std::uint64_t frames_dropped_oversize = 0;
  std::uint64_t fragments_dropped = 0;        // FU-A without start, JPEG offset gaps
  std::uint64_t malformed_packets = 0;
  std::uint64_t unsupported_packets = 0;      // STAP-B, MTAP, FU-B, reserved JPEG types
};

class Depacketizer {
 public:
  virtual ~Depacketizer() = default;
  // loss_before: packets were lost (or dropped) right before this one.
  virtual void push(const RtpPacket& packet, bool loss_before, Nanos arrival_ns, EncodedFrameSink& sink) = 0;
  virtual void reset() = 0;
  [[nodiscard]] const DepacketizerStats& stats() const { return stats_; }

 protected:
  DepacketizerStats stats_;
};

// H.264 NAL unit types (RFC 6184 §5.2, H.264 table 7-1).
constexpr std::uint8_t kNalIdrSlice = 5;
constexpr std::uint8_t kNalSps = 7;
constexpr std::uint8_t kNalPps = 8;
constexpr std::uint8_t kNalStapA = 24;
constexpr std::uint8_t kNalFuA = 28;

class H264Depacketizer final : public Depacketizer {
 public:
  explicit H264Depacketizer(std::size_t max_access_unit_bytes = 2 * 1024 * 1024);

  // Parameter sets from sprop-parameter-sets: put in front of IDR access units until the
  // stream sends its own (in-band ones win, ONVIF Streaming §5.1.3).
  void set_parameter_sets(const std::vector<std::vector<std::uint8_t>>& nals);

  void push(const RtpPacket& packet, bool loss_before, Nanos arrival_ns, EncodedFrameSink& sink) override;
  void reset() override;

 private:
  void append_nal(std::span<const std::uint8_t> nal);
  void emit(EncodedFrameSink& sink);
  void discard_au();

  std::vector<std::uint8_t> au_;        // Annex-B, capacity fixed at construction
  std::size_t au_size_ = 0;
  std::vector<std::uint8_t> out_;       // parameter sets + AU when they must go in front
  std::vector<std::uint8_t> sps_;
  std::vector<std::uint8_t> pps_;
  std::size_t sps_size_ = 0;
  std::size_t pps_size_ = 0;
  bool au_open_ = false;
  bool au_damaged_ = false;
  bool au_has_idr_ = false;
  bool au_has_sps_ = false;
  bool au_overflow_ = false;
  bool have_idr_ = false;
  std::uint32_t au_timestamp_ = 0;
  std::size_t fu_start_ = 0;            // offset in au_ of the NAL being reassembled
  bool fu_open_ = false;
  Nanos last_arrival_ns_ = 0;
};

class JpegDepacketizer final : public Depacketizer {
 public:
  explicit JpegDepacketizer(std::size_t max_frame_bytes = 2 * 1024 * 1024);

  // For frames wider or taller than 2040 px, whose header fields are 0 (SDP x-dimensions).
  void set_fallback_dimensions(int width_px, int height_px) {
    fallback_width_px_ = width_px;
    fallback_height_px_ = height_px;
  }

  void push(const RtpPacket& packet, bool loss_before, Nanos arrival_ns, EncodedFrameSink& sink) override;
  void reset() override;

 private:
  bool start_frame(std::span<const std::uint8_t> payload, std::size_t& scan_offset);
  void discard_frame();

  std::vector<std::uint8_t> frame_;
  std::size_t max_scan_bytes_;
  std::size_t frame_size_ = 0;
  std::size_t header_size_ = 0;
  std::size_t next_offset_ = 0;
  std::uint32_t timestamp_ = 0;
  bool open_ = false;
  int fallback_width_px_ = 0;
  int fallback_height_px_ = 0;
  // Tables cached per Q for 128 <= Q < 255 sent with Length 0 later (§3.1.8).
  std::array<std::array<std::uint8_t, 128>, 127> cached_tables_{};
  std::array<std::uint8_t, 127> cached_length_{};
};

// RFC 2435 Appendix A: luma then chroma tables for Q 1..99, in zig-zag order. Exposed for
// the test that compares them with libjpeg's DQT.
void make_jpeg_quant_tables(int q, std::span<std::uint8_t, 128> out);

}  // namespace sen3bot::camera
