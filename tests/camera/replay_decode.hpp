#pragma once
// Depacketizes and decodes the server side of a recorded RTSP/TCP session: the same path as
// the live client (demux, SDP, RTP, depacketizer, decoder), summarised for comparison.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/decoder.hpp"
#include "sen3bot/camera/depacketizer.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/camera/sdp.hpp"

namespace sen3bot::camera::testing {

struct ReplaySummary {
  std::string codec;
  std::uint64_t rtp_packets = 0;
  std::uint64_t frames_emitted = 0;
  std::uint64_t frames_decoded = 0;
  std::uint64_t decode_errors = 0;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::string encoded_md5;  // of every emitted access unit / JPEG, concatenated

  [[nodiscard]] std::string to_text() const {
    return "codec " + codec + "\nrtp_packets " + std::to_string(rtp_packets) + "\nframes_emitted " +
           std::to_string(frames_emitted) + "\nframes_decoded " + std::to_string(frames_decoded) + "\ndecode_errors " +
           std::to_string(decode_errors) + "\nsize " + std::to_string(width_px) + "x" + std::to_string(height_px) +
           "\nencoded_md5 " + encoded_md5 + "\n";
  }
};

inline ReplaySummary replay_decode(const std::vector<std::uint8_t>& stream) {
  struct Sink : EncodedFrameSink {
    std::unique_ptr<FrameDecoder> decoder;
    std::unique_ptr<FramePool> pool = std::move(FramePool::create(3, 1280, 720, PixelFormat::bgr8).value());
    std::string all;
    std::uint64_t frames = 0;
    void on_frame(const EncodedFrame& f) override {
      ++frames;
      all.append(reinterpret_cast<const char*>(f.data.data()), f.data.size());
      if (!decoder) decoder = std::move(FrameDecoder::create(f.codec, DecoderOptions{}).value());
      (void)decoder->decode(f, *pool, 0);
    }
  } sink;
  ReplaySummary out;
  std::unique_ptr<Depacketizer> depacketizer;
  int payload_type = -1;
  std::size_t pos = 0;
  while (pos < stream.size()) {
    auto item = demux_next(std::span<const std::uint8_t>(stream.data() + pos, stream.size() - pos));
    if (!item || item->kind == DemuxKind::need_more) break;
    if (item->kind == DemuxKind::message && item->message.body.starts_with("v=0")) {
      auto sdp = parse_sdp(item->message.body);
      if (sdp && sdp->first_supported_video()) {
        const SdpMedia& v = *sdp->first_supported_video();
        payload_type = v.payload_type;
        out.codec = to_string(v.codec);
        if (v.codec == VideoCodec::h264) {
          auto h = std::make_unique<H264Depacketizer>();
          h->set_parameter_sets(v.parameter_sets);
          depacketizer = std::move(h);
        } else {
          depacketizer = std::make_unique<JpegDepacketizer>();
        }
      }
    } else if (item->kind == DemuxKind::interleaved && item->channel == 0 && depacketizer) {
      auto packet = parse_rtp(item->payload);
      if (packet && packet->payload_type == payload_type) {
        ++out.rtp_packets;
        depacketizer->push(*packet, false, 0, sink);
      }
    }
    pos += item->consumed;
  }
  out.frames_emitted = sink.frames;
  if (sink.decoder) {
    out.frames_decoded = sink.decoder->stats().frames_decoded;
    out.decode_errors = sink.decoder->stats().decode_errors;
    out.width_px = sink.decoder->stats().source_width_px;
    out.height_px = sink.decoder->stats().source_height_px;
  }
  out.encoded_md5 = md5_hex(sink.all);
  return out;
}

}  // namespace sen3bot::camera::testing
