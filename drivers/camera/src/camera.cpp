#include "sen3bot/camera/camera.hpp"

#include <poll.h>

#include <algorithm>

namespace sen3bot::camera {

class Camera::Sink final : public EncodedFrameSink {
 public:
  explicit Sink(Camera& camera) : camera_(camera) {}
  void on_frame(const EncodedFrame& frame) override { camera_.on_frame(frame); }

 private:
  Camera& camera_;
};

Result<std::unique_ptr<Camera>> Camera::create(CameraConfig config, hal::Clock& clock) {
  if (config.downscale != 1 && config.downscale != 2 && config.downscale != 4) {
    return Error(Errc::config, "camera downscale must be 1, 2 or 4");
  }
  auto pool = FramePool::create(config.frame_pool_slots, config.max_width_px, config.max_height_px, config.format);
  if (!pool) return pool.error();
  std::unique_ptr<Camera> camera(new Camera(std::move(config), clock, std::move(*pool)));
  auto client = RtspClient::create(camera->config_.rtsp, *camera->sink_);
  if (!client) return client.error();
  camera->client_ = std::move(*client);
  return camera;
}

Camera::Camera(CameraConfig config, hal::Clock& clock, std::unique_ptr<FramePool> pool)
    : config_(std::move(config)), clock_(clock), pool_(std::move(pool)), sink_(std::make_unique<Sink>(*this)) {}

Camera::~Camera() { stop(); }

Status Camera::start() {
  if (running_.exchange(true)) return {};
  thread_ = std::thread([this] { run(); });
  return {};
}

void Camera::stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}

void Camera::on_frame(const EncodedFrame& frame) {
  if (config_.decode_limit_frames > 0 && decoder_ && decoder_->stats().frames_decoded >= config_.decode_limit_frames) {
    return;
  }
  if (!decoder_ || decoder_codec_ != frame.codec) {
    DecoderOptions options;
    options.downscale = config_.downscale;
    options.max_frame_bytes = config_.rtsp.max_frame_bytes;
    auto decoder = FrameDecoder::create(frame.codec, options);
    if (!decoder) return;
    decoder_ = std::move(*decoder);
    decoder_codec_ = frame.codec;
  }
  if (decoder_->decode(frame, *pool_, clock_.now()) && frame.last_packet_ns > 0) {
    const hal::Nanos done = clock_.now();
    latencies_ms_[latency_count_ % kLatencySamples] = static_cast<double>(done - frame.last_packet_ns) / 1e6;
    ++latency_count_;
  }
}

void Camera::step(hal::Nanos now_ns) {
  client_->step(now_ns);
  if (client_->failed()) failed_.store(true, std::memory_order_release);
  // Status for non-real-time observers, refreshed every pass (a few hundred bytes; the error
  // text reuses its buffer once it has held the longest message).
  std::lock_guard lock(status_mutex_);
  status_.state = client_->state();
  status_.stream = client_->stream();
  status_.rtsp = client_->stats();
  if (client_->depacketizer()) status_.depacketizer = client_->depacketizer()->stats();
  if (decoder_) status_.decoder = decoder_->stats();
  status_.last_error.assign(client_->last_error());
  if (latency_count_ != published_status_at_) {
    published_status_at_ = latency_count_;
    const std::size_t k = std::min(latency_count_, kLatencySamples);
    double sorted[kLatencySamples];
    std::copy(latencies_ms_, latencies_ms_ + k, sorted);
    std::sort(sorted, sorted + k);
    status_.latency_ms_p50 = sorted[k / 2];
    status_.latency_ms_max = sorted[k - 1];
  }
}

void Camera::close(hal::Nanos now_ns) { client_->stop(now_ns); }

void Camera::run() {
  while (running_.load(std::memory_order_acquire)) {
    step(clock_.now());
    int fds[4];
    const std::size_t n = client_->poll_fds(fds, 4);
    pollfd pfds[4];
    for (std::size_t i = 0; i < n; ++i) pfds[i] = pollfd{fds[i], POLLIN, 0};
    (void)::poll(pfds, n, config_.poll_period_ms);
  }
  close(clock_.now());
}

CameraStatus Camera::status() const {
  std::lock_guard lock(status_mutex_);
  return status_;
}

}  // namespace sen3bot::camera
