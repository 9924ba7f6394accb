// The camera's row in steady state: once the stream plays, a step (RTSP/RTP I/O, depacketizing,
// decoding into the frame pool) makes no C++ allocation. libavcodec's H.264 decoder itself
// mallocs for every frame it decodes (packet references, side data: about 36 per frame here);
// that is printed, not asserted: the one exception to the steady-state rule, kept on a thread
// of its own. Own executable: it counts global allocations. Against
// Debian's gst-rtsp-server.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "alloc_counter.hpp"
#include "camera_task.hpp"
#include "peer_process.hpp"

namespace sen3bot::firmware {
namespace {

TEST(CameraTaskAllocation, SteadyStateStepsMakeNoCxxAllocation) {
  camera::testing::PeerProcess peer("/usr/bin/python3", {SEN3BOT_SOURCE_DIR "/tests/camera/peers/rtsp_server.py"});
  ASSERT_TRUE(peer.ready()) << peer.error();
  camera::CameraConfig config;
  config.rtsp.url = "rtsp://127.0.0.1:" + std::to_string(peer.port()) + "/h264";
  config.max_width_px = 640;
  config.max_height_px = 480;
  hal::PosixBoard board;
  tasks::Bus bus;
  CameraTask task(config, board, bus);
  std::pmr::monotonic_buffer_resource arena;
  ASSERT_TRUE(task.init(arena));
  hal::Clock& clock = board.clock();
  std::uint64_t cycle = 0;
  auto run_until = [&](std::uint64_t frames, hal::Nanos limit) {
    const hal::Nanos end = clock.now() + limit;
    while (clock.now() < end && task.camera()->frames().latest_sequence() < frames) {
      const hal::Nanos now = clock.now();
      task.step({now, now, cycle++});
      clock.sleep_until(now + hal::millis(20));  // the row's period
    }
  };
  run_until(20, hal::seconds(20));  // connect, describe, play, first frames: these allocate
  ASSERT_GE(task.camera()->frames().latest_sequence(), 20u) << task.camera()->status().last_error;
  mem::testing::AllocationScope scope;
  run_until(80, hal::seconds(20));
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  const std::uint64_t frames = task.camera()->frames().latest_sequence();
  task.shutdown();
  std::printf("camera steady state: %llu frames, %llu operator new, %llu malloc\n",
              static_cast<unsigned long long>(frames - 20), static_cast<unsigned long long>(allocations),
              static_cast<unsigned long long>(malloc_calls));
  EXPECT_GE(frames, 80u);
  EXPECT_EQ(allocations, 0u);
}

}  // namespace
}  // namespace sen3bot::firmware
