// The camera's row of the task table: the firmware, configured with a camera, runs the RTSP
// client and the decoder on the table's "camera" thread against Debian's gst-rtsp-server
// (tests/camera/peers/rtsp_server.py), in real time, and frames arrive in the pool; against a
// camera that offers only H.265 the row gives up once, says why, and the firmware runs on.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "camera_test_util.hpp"
#include "config.hpp"
#include "fake_camera.hpp"
#include "firmware.hpp"
#include "peer_process.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

std::string camera_config(const std::string& url) {
  return "robot: { name: camera-test }\n"
         "run: { clock: realtime, duration_s: 0 }\n"
         "realtime: { lock_memory: false }\n"
         "threads: { camera: { realtime: false }, control: { realtime: false }, background: { realtime: false } }\n"
         "tasks:\n"
         "  health: { arena_bytes: 4KiB }\n"
         "  telemetry: { arena_bytes: 4KiB, status_period_s: 0.5 }\n"
         "  camera: { arena_bytes: 1KiB }\n"
         "devices:\n"
         "  camera: { url: " + url + ", transport: tcp, max_width_px: 640, max_height_px: 480, format: gray8 }\n";
}

TEST(CameraTask, TheCameraRowDecodesFramesOnItsOwnThread) {
  camera::testing::PeerProcess peer("/usr/bin/python3", {SEN3BOT_SOURCE_DIR "/tests/camera/peers/rtsp_server.py"});
  ASSERT_TRUE(peer.ready()) << peer.error();
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(peer.port()) + "/h264";
  // With the live view: the camera's frames go out as JPEG on /camera/image.
  Result<FirmwareConfig> config = parse_config(camera_config(url) +
                                                   "view: { port: 0, channels: { camera: 0.2 } }\n",
                                               "camera.yaml");
  ASSERT_TRUE(config) << config.error().c_str();
  ASSERT_TRUE(config->devices.has_camera);
  config->tasks["view"].arena_bytes = 2 * 1024 * 1024;

  hal::PosixBoard board;
  std::FILE* sink = std::fopen("/dev/null", "w");
  Firmware fw(*config, board, sink);
  const Status started = fw.init();
  ASSERT_TRUE(started) << started.error().c_str();
  ASSERT_NE(fw.camera_frames(), nullptr);
  ASSERT_TRUE(fw.scheduler().start());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline && fw.camera_frames()->latest_sequence() < 30)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  fw.shutdown();
  std::fclose(sink);

  camera::FrameHandle frame = fw.camera_frames()->acquire_latest();
  ASSERT_TRUE(frame) << fw.camera()->status().last_error;
  EXPECT_GE(frame.ref().sequence, 30u);
  EXPECT_EQ(frame.ref().width_px, 640u);
  EXPECT_EQ(frame.ref().height_px, 360u);
  const camera::CameraStatus status = fw.camera()->status();
  EXPECT_EQ(status.decoder.decode_errors, 0u);

  // The view row found the camera row's frames and sent them as JPEG, shrunk to 320 wide.
  ASSERT_NE(fw.view(), nullptr);
  view::ChannelBoard& channels = fw.view()->server()->board();
  std::size_t image = channels.channel_count();
  for (std::size_t i = 0; i < channels.channel_count(); ++i)
    if (channels.spec(i).topic == "/camera/image") image = i;
  ASSERT_LT(image, channels.channel_count());
  EXPECT_GE(channels.published(image), 3u);
  const view::Publication& jpeg = channels.take(image);
  const std::string_view message(jpeg.payload(0).data(), jpeg.payload(0).size());
  EXPECT_NE(message.find(R"("format":"jpeg")"), std::string_view::npos);
  EXPECT_NE(message.find(R"("data":"/9j/)"), std::string_view::npos) << "base64 of a JPEG's FF D8 FF";

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

std::size_t row_of(const tasks::Scheduler& scheduler, std::string_view name) {
  for (std::size_t i = 0; i < scheduler.task_count(); ++i)
    if (scheduler.spec(i).name == name) return i;
  return scheduler.task_count();
}

TEST(CameraTask, ACameraThatFailedForGoodIsReportedAndTheFirmwareRunsWithoutIt) {
  camera::testing::FakeCamera fake({{"DESCRIBE", camera::testing::read_fixture("rtsp/anjvision_describe.txt")}});
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(fake.port()) + "/stream0";
  Result<FirmwareConfig> config = parse_config(camera_config(url), "camera.yaml");
  ASSERT_TRUE(config) << config.error().c_str();

  hal::PosixBoard board;
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  Firmware fw(*config, board, out);
  ASSERT_TRUE(fw.init());
  ASSERT_TRUE(fw.scheduler().start());
  // Long enough for three reconnects at the default backoff (250, 500, 1000 ms) had the
  // failure been taken for a passing one.
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  const tasks::Scheduler& scheduler = fw.scheduler();
  const std::size_t camera_row = row_of(scheduler, "camera");
  const std::size_t health_row = row_of(scheduler, "health");
  ASSERT_LT(camera_row, scheduler.task_count());
  ASSERT_LT(health_row, scheduler.task_count());
  const std::uint64_t health_runs = scheduler.counters(health_row).runs.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_GT(scheduler.counters(health_row).runs.load(), health_runs);  // the firmware runs on
  tasks::Sample<tasks::HealthReport> report;
  ASSERT_TRUE(fw.bus().health.read(report));
  fw.shutdown();

  EXPECT_TRUE(fw.camera()->failed());
  const camera::CameraStatus status = fw.camera()->status();
  EXPECT_EQ(status.state, camera::ClientState::failed);
  EXPECT_EQ(status.last_error, "the camera offers only H265 video (rtpmap H265/90000); supported: H264, JPEG");
  EXPECT_EQ(fake.accepted(), 1);
  EXPECT_EQ(report.value.failed_count, 1u);
  EXPECT_EQ(report.value.failed_mask, std::uint64_t{1} << camera_row);
  EXPECT_EQ(report.value.stalled_count, 0u);
  EXPECT_FALSE(report.value.ok);
  EXPECT_EQ(fw.camera_frames()->latest_sequence(), 0u);

  std::fflush(out);
  std::rewind(out);
  std::string text;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, out)) text.append(buf, n);
  std::fclose(out);
  EXPECT_NE(text.find("error   camera: gave up: the camera offers only H265 video (rtpmap H265/90000); supported: H264, JPEG"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("error   health: task camera failed: running without its device"), std::string::npos) << text;
  EXPECT_NE(text.find("health DEGRADED (0 stalled, 1 failed, 0 missing)"), std::string::npos) << text;
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
