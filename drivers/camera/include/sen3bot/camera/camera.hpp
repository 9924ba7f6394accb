#pragma once
// The camera as the firmware sees it: the RTSP client and the decoder, stepped by a scheduler
// task on its own non-real-time thread (step()) or by the camera's own thread (start()), publish
// frames to a fixed pool; real-time tasks read the newest frame with frames().acquire_latest(),
// which never blocks or allocates.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "sen3bot/camera/decoder.hpp"
#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/camera/rtsp_client.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::camera {

struct CameraConfig {
  RtspClientConfig rtsp;                 // URL, credentials, transport, timeouts (see there)
  std::size_t frame_pool_slots = 4;      // >= 3; one more per reader that holds frames long
  std::uint32_t max_width_px = 1280;     // pool slot size; frames are shrunk to fit, never enlarged
  std::uint32_t max_height_px = 720;
  PixelFormat format = PixelFormat::bgr8;  // bgr8 for display/detection, gray8 for cheap work
  int downscale = 1;                     // 1, 2 or 4: divide the source size before fitting
  int poll_period_ms = 5;                // longest sleep of the camera thread between steps
  std::uint64_t decode_limit_frames = 0;  // stop decoding after this many frames; 0: never
};

struct CameraStatus {
  ClientState state = ClientState::idle;  // failed: given up for good, last_error says why
  StreamInfo stream;
  RtspClientStats rtsp;
  DepacketizerStats depacketizer;
  DecoderStats decoder;
  double latency_ms_p50 = 0;  // last RTP packet of a frame -> frame readable, over the last 256
  double latency_ms_max = 0;
  std::string last_error;
  [[nodiscard]] bool failed() const { return state == ClientState::failed; }
};

class Camera {
 public:
  static Result<std::unique_ptr<Camera>> create(CameraConfig config, hal::Clock& clock);
  ~Camera();
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  // Runs step() on the camera's own thread, waiting on its sockets in between.
  Status start();
  void stop();  // TEARDOWN and join; idempotent

  // One non-blocking pass: RTSP/RTP I/O, depacketizing, decoding what arrived, the status.
  // For a caller with its own loop; not together with start().
  void step(hal::Nanos now_ns);
  // Ends the session (TEARDOWN) of a stepped camera.
  void close(hal::Nanos now_ns);

  [[nodiscard]] FramePool& frames() { return *pool_; }
  [[nodiscard]] CameraStatus status() const;  // copies under a mutex: not for real-time code
  // The client gave up for good (see RtspClient::step); any thread, lock-free.
  [[nodiscard]] bool failed() const { return failed_.load(std::memory_order_acquire); }

 private:
  class Sink;
  Camera(CameraConfig config, hal::Clock& clock, std::unique_ptr<FramePool> pool);
  void run();
  void on_frame(const EncodedFrame& frame);

  CameraConfig config_;
  hal::Clock& clock_;
  std::unique_ptr<FramePool> pool_;
  std::unique_ptr<Sink> sink_;
  std::unique_ptr<RtspClient> client_;
  std::unique_ptr<FrameDecoder> decoder_;
  VideoCodec decoder_codec_ = VideoCodec::unknown;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> failed_{false};
  mutable std::mutex status_mutex_;
  CameraStatus status_;
  static constexpr std::size_t kLatencySamples = 256;
  double latencies_ms_[kLatencySamples] = {};
  std::size_t latency_count_ = 0;
  std::size_t published_status_at_ = 0;
};

}  // namespace sen3bot::camera
