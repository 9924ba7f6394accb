// The reference sender (tools/detector_replay.py: Python's struct and zlib, an encoder written
// apart from ours) replaying a box file over real UDP, and the gate decoding what arrives.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "sen3bot/detector/protocol.hpp"

namespace sen3bot::detector {
namespace {

constexpr hal::Nanos kNow = 50'000'000'000;

TEST(DetectorDatagram, TheReferenceSendersDatagramsArriveOverUdpAndDecode) {
  const int sock = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(sock, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  ASSERT_EQ(::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  socklen_t len = sizeof addr;
  ASSERT_EQ(::getsockname(sock, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  const std::string boxes = ::testing::TempDir() + "detector_boxes.jsonl";
  std::ofstream(boxes) << "# two frames\n"
                          "{\"t_s\": 0.0, \"boxes\": [[100, 50, 220, 700, 0.87, 0], [600, 10, 640, 300, 0.4, 56]]}\n"
                          "\n"
                          "{\"t_s\": 0.05, \"boxes\": []}\n";
  const std::string command = "python3 " SEN3BOT_SOURCE_DIR "/tools/detector_replay.py --to 127.0.0.1:" +
                              std::to_string(ntohs(addr.sin_port)) + " --source 3 --first-sequence 20 --latency 0.02 " +
                              boxes + " 2>/dev/null";
  const auto unix_ns = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  // The sender stamps a frame 20 ms before it sends it, and it sends after this: a busy machine
  // may delay the reading below by any amount, which the age must include, but not more.
  const std::int64_t launched_unix = unix_ns();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  DetectionGate gate;
  std::vector<detector::Detections> frames;
  std::int64_t first_read_unix = 0;
  std::uint8_t buffer[2048];
  pollfd pfd{sock, POLLIN, 0};
  while (frames.size() < 2 && ::poll(&pfd, 1, 2000) == 1) {
    const ssize_t n = ::recv(sock, buffer, sizeof buffer, 0);
    ASSERT_GT(n, 0);
    const std::int64_t unix_now = unix_ns();
    if (frames.empty()) first_read_unix = unix_now;
    detector::Detections out;
    ASSERT_TRUE(gate.accept(std::span(buffer, static_cast<std::size_t>(n)), kNow, unix_now, out));
    frames.push_back(out);
  }
  ::close(sock);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].source, 3u);
  EXPECT_EQ(frames[0].sequence, 20u);
  EXPECT_EQ(frames[1].sequence, 21u);
  ASSERT_EQ(frames[0].count, 2);
  EXPECT_EQ(frames[0].boxes[0].u0, 100.0f);
  EXPECT_EQ(frames[0].boxes[0].v1, 700.0f);
  EXPECT_FLOAT_EQ(frames[0].boxes[0].confidence, 0.87f);
  EXPECT_EQ(frames[0].boxes[1].class_id, 56);
  EXPECT_EQ(frames[1].count, 0);
  // Sent 20 ms after capture: at least that old on the firmware's clock when read, and no older
  // than the time from the sender's start to the reading plus those 20 ms (and a millisecond
  // for the clocks' rounding).
  EXPECT_LT(frames[0].capture_ns, kNow - 15'000'000);
  EXPECT_GE(frames[0].capture_ns, kNow - (first_read_unix - launched_unix) - 21'000'000);
}

}  // namespace
}  // namespace sen3bot::detector
