#include "sen3bot/camera/decoder.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "sen3bot/image/image_file.hpp"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/frame.h>
#include <libavutil/imgutils.h>
#include <libswscale/swscale.h>
}

namespace sen3bot::camera {

void fit_output_size(std::uint32_t source_w, std::uint32_t source_h, int downscale, std::uint32_t max_w,
                     std::uint32_t max_h, std::uint32_t& out_w, std::uint32_t& out_h) {
  const std::uint32_t d = downscale < 1 ? 1u : static_cast<std::uint32_t>(downscale);
  std::uint32_t w = std::max<std::uint32_t>(1, source_w / d);
  std::uint32_t h = std::max<std::uint32_t>(1, source_h / d);
  if (w > max_w || h > max_h) {
    const double scale = std::min(static_cast<double>(max_w) / w, static_cast<double>(max_h) / h);
    w = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(w * scale));
    h = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(h * scale));
  }
  out_w = w;
  out_h = h;
}

namespace {

class JpegDecoder final : public FrameDecoder {
 public:
  explicit JpegDecoder(const DecoderOptions& options) : options_(options) {}

  bool decode(const EncodedFrame& frame, FramePool& pool, hal::Nanos now_ns) override {
    ++stats_.frames_in;
    const int channels = pool.format() == PixelFormat::gray8 ? 1 : 3;
    if (!image::decode_jpeg(frame.data, channels, decoded_)) {
      ++stats_.decode_errors;
      return false;
    }
    stats_.source_width_px = decoded_.width_px;
    stats_.source_height_px = decoded_.height_px;
    const int slot = pool.begin_write();
    if (slot < 0) {
      ++stats_.no_free_slot;
      return false;
    }
    std::uint32_t w = 0;
    std::uint32_t h = 0;
    fit_output_size(stats_.source_width_px, stats_.source_height_px, options_.downscale, pool.width_px(), pool.height_px(), w, h);
    cv::Mat out(static_cast<int>(h), static_cast<int>(w), pool.format() == PixelFormat::gray8 ? CV_8UC1 : CV_8UC3,
                pool.slot_pixels(slot).data());
    const cv::Mat decoded(static_cast<int>(decoded_.height_px), static_cast<int>(decoded_.width_px), out.type(),
                          decoded_.pixels.data());
    if (w == stats_.source_width_px && h == stats_.source_height_px) {
      decoded.copyTo(out);
    } else {
      cv::resize(decoded, out, out.size(), 0, 0, cv::INTER_AREA);
    }
    pool.publish(slot, w, h, frame.rtp_timestamp, frame.last_packet_ns, now_ns);
    ++stats_.frames_decoded;
    return true;
  }

 private:
  DecoderOptions options_;
  image::Image decoded_;  // reused while the stream's size is unchanged
};

class H264Decoder final : public FrameDecoder {
 public:
  explicit H264Decoder(const DecoderOptions& options)
      : options_(options), padded_(options.max_frame_bytes + 2048 + AV_INPUT_BUFFER_PADDING_SIZE) {}
  ~H264Decoder() override {
    sws_freeContext(sws_);
    av_packet_free(&packet_);
    av_frame_free(&picture_);
    avcodec_free_context(&context_);
  }
  H264Decoder(const H264Decoder&) = delete;
  H264Decoder& operator=(const H264Decoder&) = delete;

  Status open() {
    const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
    if (codec == nullptr) return Error(Errc::not_supported, "libavcodec has no H.264 decoder");
    context_ = avcodec_alloc_context3(codec);
    picture_ = av_frame_alloc();
    packet_ = av_packet_alloc();
    if (context_ == nullptr || picture_ == nullptr || packet_ == nullptr) return Error(Errc::capacity, "libavcodec allocation failed");
    // Low delay, slice threads only: frame threading adds a frame of latency per thread.
    context_->flags |= AV_CODEC_FLAG_LOW_DELAY;
    context_->thread_type = FF_THREAD_SLICE;
    if (avcodec_open2(context_, codec, nullptr) < 0) return Error(Errc::io, "avcodec_open2 failed for H.264");
    return {};
  }

  bool decode(const EncodedFrame& frame, FramePool& pool, hal::Nanos now_ns) override {
    ++stats_.frames_in;
    if (frame.data.size() + AV_INPUT_BUFFER_PADDING_SIZE > padded_.size()) {
      ++stats_.decode_errors;
      return false;
    }
    std::memcpy(padded_.data(), frame.data.data(), frame.data.size());
    std::memset(padded_.data() + frame.data.size(), 0, AV_INPUT_BUFFER_PADDING_SIZE);
    packet_->data = padded_.data();
    packet_->size = static_cast<int>(frame.data.size());
    if (avcodec_send_packet(context_, packet_) < 0) {
      ++stats_.decode_errors;
      return false;
    }
    bool published = false;
    while (avcodec_receive_frame(context_, picture_) == 0) {
      if ((picture_->flags & AV_FRAME_FLAG_CORRUPT) != 0 || picture_->decode_error_flags != 0) {
        ++stats_.decode_errors;
        av_frame_unref(picture_);
        continue;
      }
      published = publish(*picture_, frame, pool, now_ns) || published;
      av_frame_unref(picture_);
    }
    return published;
  }

 private:
  bool publish(const AVFrame& picture, const EncodedFrame& frame, FramePool& pool, hal::Nanos now_ns) {
    stats_.source_width_px = static_cast<std::uint32_t>(picture.width);
    stats_.source_height_px = static_cast<std::uint32_t>(picture.height);
    const int slot = pool.begin_write();
    if (slot < 0) {
      ++stats_.no_free_slot;
      return false;
    }
    std::uint32_t w = 0;
    std::uint32_t h = 0;
    fit_output_size(stats_.source_width_px, stats_.source_height_px, options_.downscale, pool.width_px(), pool.height_px(), w, h);
    const bool gray = pool.format() == PixelFormat::gray8;
    // Cached: a new context only when the stream's size or format changes.
    sws_ = sws_getCachedContext(sws_, picture.width, picture.height, static_cast<AVPixelFormat>(picture.format),
                                static_cast<int>(w), static_cast<int>(h), gray ? AV_PIX_FMT_GRAY8 : AV_PIX_FMT_BGR24,
                                SWS_BILINEAR, nullptr, nullptr, nullptr);
    if (sws_ == nullptr) {
      ++stats_.decode_errors;
      return false;
    }
    std::uint8_t* dst[4] = {pool.slot_pixels(slot).data(), nullptr, nullptr, nullptr};
    int dst_stride[4] = {static_cast<int>(w * (gray ? 1 : 3)), 0, 0, 0};
    sws_scale(sws_, picture.data, picture.linesize, 0, picture.height, dst, dst_stride);
    pool.publish(slot, w, h, frame.rtp_timestamp, frame.last_packet_ns, now_ns);
    ++stats_.frames_decoded;
    return true;
  }

  DecoderOptions options_;
  std::vector<std::uint8_t> padded_;
  AVCodecContext* context_ = nullptr;
  AVFrame* picture_ = nullptr;
  AVPacket* packet_ = nullptr;
  SwsContext* sws_ = nullptr;
};

}  // namespace

Result<std::unique_ptr<FrameDecoder>> FrameDecoder::create(VideoCodec codec, const DecoderOptions& options) {
  if (codec == VideoCodec::jpeg) return std::unique_ptr<FrameDecoder>(std::make_unique<JpegDecoder>(options));
  if (codec == VideoCodec::h264) {
    auto decoder = std::make_unique<H264Decoder>(options);
    if (auto s = decoder->open(); !s) return s.error();
    return std::unique_ptr<FrameDecoder>(std::move(decoder));
  }
  return Error(Errc::not_supported, "no decoder for this codec");
}

}  // namespace sen3bot::camera
