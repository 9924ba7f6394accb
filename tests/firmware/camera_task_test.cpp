// The camera's row of the task table: the firmware, configured with a camera, runs the RTSP
// client and the decoder on the table's "camera" thread against Debian's gst-rtsp-server
// (tests/camera/peers/rtsp_server.py), in real time, and frames arrive in the pool.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "config.hpp"
#include "firmware.hpp"
#include "peer_process.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

std::string camera_config(const std::string& url) {
  return "robot: { name: camera-test }\n"
         "run: { clock: realtime, duration_s: 0 }\n"
         "realtime: { lock_memory: false }\n"
         "threads: { camera: { realtime: false } }\n"
         "tasks:\n"
         "  health: { arena_bytes: 4KiB }\n"
         "  telemetry: { arena_bytes: 4KiB }\n"
         "  camera: { arena_bytes: 1KiB }\n"
         "devices:\n"
         "  camera: { url: " + url + ", transport: tcp, max_width_px: 640, max_height_px: 480, format: gray8 }\n";
}

TEST(CameraTask, TheCameraRowDecodesFramesOnItsOwnThread) {
  camera::testing::PeerProcess peer("/usr/bin/python3", {SEN3BOT_SOURCE_DIR "/tests/camera/peers/rtsp_server.py"});
  ASSERT_TRUE(peer.ready()) << peer.error();
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(peer.port()) + "/h264";
  Result<FirmwareConfig> config = parse_config(camera_config(url), "camera.yaml");
  ASSERT_TRUE(config) << config.error().c_str();
  ASSERT_TRUE(config->devices.has_camera);

  hal::PosixBoard board;
  std::FILE* sink = std::fopen("/dev/null", "w");
  Firmware fw(*config, board, sink);
  ASSERT_TRUE(fw.init());
  ASSERT_NE(fw.camera_frames(), nullptr);
  ASSERT_TRUE(fw.scheduler().start());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline && fw.camera_frames()->latest_sequence() < 30)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  fw.shutdown();
  std::fclose(sink);

  camera::FrameHandle frame = fw.camera_frames()->acquire_latest();
  ASSERT_TRUE(frame) << fw.camera()->camera()->status().last_error;
  EXPECT_GE(frame.ref().sequence, 30u);
  EXPECT_EQ(frame.ref().width_px, 640u);
  EXPECT_EQ(frame.ref().height_px, 360u);
  const camera::CameraStatus status = fw.camera()->camera()->status();
  EXPECT_EQ(status.decoder.decode_errors, 0u);

  // The row ran on its own thread at its period, and its cost was measured.
  std::size_t row = fw.scheduler().task_count();
  for (std::size_t i = 0; i < fw.scheduler().task_count(); ++i)
    if (fw.scheduler().spec(i).name == "camera") row = i;
  ASSERT_LT(row, fw.scheduler().task_count());
  const tasks::TaskStats stats = fw.scheduler().stats(row);
  EXPECT_EQ(stats.thread, "camera");
  EXPECT_GT(stats.runs, 30u);
  EXPECT_GT(stats.cpu_max_ns, 0);
  std::printf("camera row: %llu runs, CPU mean %.2f ms, max %.2f ms (budget %.1f ms)\n",
              static_cast<unsigned long long>(stats.runs), static_cast<double>(stats.cpu_mean_ns) * 1e-6,
              static_cast<double>(stats.cpu_max_ns) * 1e-6, static_cast<double>(stats.budget_us) * 1e-3);
}

TEST(CameraTask, BadCameraKeysAreConfigurationErrors) {
  auto message = [](const std::string& camera) {
    Result<FirmwareConfig> r = parse_config(
        "robot: { name: x }\nrun: { clock: realtime, duration_s: 0 }\ntasks: {}\ndevices:\n  camera: " + camera + "\n",
        "robot.yaml");
    return r ? std::string() : std::string(r.error().message());
  };
  EXPECT_NE(message("{ url: http://cam/stream }").find("devices.camera.url: expected rtsp://"), std::string::npos);
  EXPECT_NE(message("{ url: rtsp://cam/s, transport: sctp }").find("devices.camera.transport: expected tcp or udp"),
            std::string::npos);
  EXPECT_NE(message("{ url: rtsp://cam/s, downscale: 3 }").find("devices.camera.downscale: expected 1, 2 or 4"),
            std::string::npos);
  EXPECT_NE(message("{ url: rtsp://cam/s, fps: 30 }").find("devices.camera.fps: unknown key"), std::string::npos);
  EXPECT_NE(message("{ transport: tcp }").find("devices.camera.url: missing"), std::string::npos);
}

}  // namespace
}  // namespace sen3bot::firmware
