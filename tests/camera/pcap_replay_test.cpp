// A recorded RTSP/TCP session (tests/data/camera/capture/*.pcap, readable by tshark) replayed
// through demux, depacketizer and decoder: the result must match what was recorded with it.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "pcap_io.hpp"
#include "replay_decode.hpp"

namespace sen3bot::camera {
namespace {

TEST(PcapReplay, H264SessionDecodesIdentically) {
  const std::string dir = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/camera/capture/";
  std::vector<std::uint8_t> stream;
  ASSERT_TRUE(testing::read_pcap_server_stream(dir + "gst_h264_tcp.pcap", stream));
  ASSERT_GT(stream.size(), 1000u);
  const auto summary = testing::replay_decode(stream);
  std::ifstream expected_file(dir + "gst_h264_tcp.expected");
  std::stringstream expected;
  expected << expected_file.rdbuf();
  EXPECT_EQ(summary.to_text(), expected.str());
  EXPECT_GT(summary.frames_decoded, 10u);
  EXPECT_EQ(summary.decode_errors, 0u);
}

}  // namespace
}  // namespace sen3bot::camera

namespace sen3bot::camera {
namespace {

// The capture is a real pcap: tshark's RTSP dissector finds the session's requests in it.
TEST(PcapReplay, TsharkReadsTheCapture) {
  const std::string path = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/camera/capture/gst_h264_tcp.pcap";
  const std::string cmd = "tshark -r '" + path + "' -Y rtsp.request -T fields -e rtsp.method 2>/dev/null";
  std::string out;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) out += buf;
  const int status = ::pclose(pipe);
  ASSERT_EQ(status, 0) << "tshark missing or failed (Debian package tshark)";
  EXPECT_EQ(out, "OPTIONS\nDESCRIBE\nSETUP\nPLAY\n");
}

}  // namespace
}  // namespace sen3bot::camera
