#pragma once
// Decoders from encoded frames into the frame pool: H.264 with libavcodec, JPEG with
// libjpeg-turbo (image_file.hpp). Run on a non-real-time thread. A frame that fails to decode is
// counted and dropped, never fatal. The libraries allocate inside their decode calls (libjpeg
// work memory per image, libavcodec reference pictures); our side reuses fixed buffers.
#include <cstdint>
#include <memory>

#include "sen3bot/camera/depacketizer.hpp"
#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera {

struct DecoderStats {
  std::uint64_t frames_in = 0;
  std::uint64_t frames_decoded = 0;  // published to the pool
  std::uint64_t decode_errors = 0;   // corrupt or undecodable: dropped
  std::uint64_t no_free_slot = 0;    // every pool slot pinned by readers: dropped
  std::uint32_t source_width_px = 0; // of the last decoded picture
  std::uint32_t source_height_px = 0;
};

// Output: the source size divided by downscale, shrunk further (keeping the aspect ratio)
// to fit the pool's slots; never enlarged.
struct DecoderOptions {
  int downscale = 1;  // 1, 2, 4: the detector may want fewer pixels
  std::size_t max_frame_bytes = 2 * 1024 * 1024;
};

class FrameDecoder {
 public:
  virtual ~FrameDecoder() = default;
  static Result<std::unique_ptr<FrameDecoder>> create(VideoCodec codec, const DecoderOptions& options);

  // Decodes one frame and publishes what it yields; true when a frame was published.
  virtual bool decode(const EncodedFrame& frame, FramePool& pool, hal::Nanos now_ns) = 0;
  [[nodiscard]] const DecoderStats& stats() const { return stats_; }

 protected:
  DecoderStats stats_;
};

// Output size for a source picture under options and pool limits.
void fit_output_size(std::uint32_t source_w, std::uint32_t source_h, int downscale, std::uint32_t max_w,
                     std::uint32_t max_h, std::uint32_t& out_w, std::uint32_t& out_h);

}  // namespace sen3bot::camera
