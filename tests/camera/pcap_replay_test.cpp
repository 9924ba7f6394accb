// A recorded RTSP/TCP session (tests/data/camera/capture/*.pcap, readable by tshark) replayed
// through demux, depacketizer and decoder: the result must match what was recorded with it.
#include <gtest/gtest.h>

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
