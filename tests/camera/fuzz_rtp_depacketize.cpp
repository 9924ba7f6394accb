// Fuzz target: RTP parsing, the reorder buffer and both depacketizers. The input is a list of
// packets, each prefixed by a 16-bit big-endian length (the interleaved framing without '$').
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/camera/depacketizer.hpp"
#include "sen3bot/camera/rtp.hpp"

namespace {
struct Check : sen3bot::camera::EncodedFrameSink {
  void on_frame(const sen3bot::camera::EncodedFrame& f) override {
    if (f.data.empty()) __builtin_trap();
  }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::camera;
  static H264Depacketizer h264(64 * 1024);
  static JpegDepacketizer jpeg(64 * 1024);
  h264.reset();
  jpeg.reset();
  ReorderBuffer reorder(8, 2048);
  SequenceTracker seq;
  Check sink;
  std::span<const std::uint8_t> in(data, size);
  while (in.size() >= 2) {
    const std::size_t n = (std::size_t{in[0]} << 8) | in[1];
    in = in.subspan(2);
    const std::size_t take = n < in.size() ? n : in.size();
    auto packet = parse_rtp(in.subspan(0, take));
    in = in.subspan(take);
    if (!packet) continue;
    std::uint64_t ext = 0;
    if (seq.update(packet->sequence, ext) != SequenceTracker::Verdict::accept) continue;
    if (reorder.push(ext, packet->payload) == ReorderBuffer::PushResult::ahead) {
      ReorderBuffer::Released r;
      (void)reorder.pop(r, true);
    }
    ReorderBuffer::Released r;
    while (reorder.pop(r)) {
    }
    Depacketizer& d = packet->payload_type == 26 ? static_cast<Depacketizer&>(jpeg) : h264;
    d.push(*packet, (packet->sequence & 0x1F) == 0x1F, 0, sink);
  }
  return 0;
}
