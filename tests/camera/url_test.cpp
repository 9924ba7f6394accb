#include <gtest/gtest.h>

#include "sen3bot/camera/rtsp_url.hpp"

namespace sen3bot::camera {
namespace {

TEST(RtspUrl, ParsesUserinfoPortAndPath) {
  auto url = parse_rtsp_url("rtsp://admin:se%40cret@192.168.1.5:8554/h264?x=1");
  ASSERT_TRUE(url.ok()) << url.error().message();
  EXPECT_EQ(url->user, "admin");
  EXPECT_EQ(url->password, "se@cret");
  EXPECT_EQ(url->host, "192.168.1.5");
  EXPECT_EQ(url->port, 8554);
  EXPECT_EQ(url->path, "/h264?x=1");
  EXPECT_EQ(url->request_uri(), "rtsp://192.168.1.5:8554/h264?x=1");
}

TEST(RtspUrl, DefaultPortAndEmptyPath) {
  auto url = parse_rtsp_url("rtsp://cam");
  ASSERT_TRUE(url.ok());
  EXPECT_EQ(url->port, kDefaultRtspPort);
  EXPECT_EQ(url->path, "/");
}

TEST(RtspUrl, RejectsBrokenContentBaseValues) {
  EXPECT_FALSE(parse_rtsp_url("rtsp://rtsp://turret2-cam.lan:554/stream1/").ok());
  EXPECT_FALSE(parse_rtsp_url("192.168.1.10:554/stream0/").ok());
  EXPECT_FALSE(parse_rtsp_url("rtsp:///path").ok());
  EXPECT_FALSE(parse_rtsp_url("rtsp://h:0/").ok());
  EXPECT_FALSE(parse_rtsp_url("rtsp://h:99999/").ok());
  EXPECT_FALSE(parse_rtsp_url("rtsp://h:12a/").ok());
  EXPECT_FALSE(parse_rtsp_url("").ok());
}

TEST(RtspUrl, StripsUserinfo) {
  EXPECT_EQ(strip_userinfo("rtsp://admin:@host/x"), "rtsp://host/x");
  EXPECT_EQ(strip_userinfo("rtsp://host/a@b"), "rtsp://host/a@b");
}

struct ResolveCase {
  const char* request;
  const char* content_base;
  const char* control;
  const char* expected;
};

// Brief §1.5 table, plus the broken Content-Base values from the field.
TEST(RtspUrl, ResolvesControlsLikeFfmpeg) {
  const ResolveCase cases[] = {
      {"rtsp://127.0.0.1:8554/h264", "rtsp://127.0.0.1:8554/h264/", "stream=0", "rtsp://127.0.0.1:8554/h264/stream=0"},
      {"rtsp://127.0.0.1:8554/h264", "rtsp://127.0.0.1:8554/h264/", "*", "rtsp://127.0.0.1:8554/h264/"},
      {"rtsp://127.0.0.1:8560/h264", "rtsp://127.0.0.1:8560/h264", "rtsp://127.0.0.1:8560/h264/trackID=0",
       "rtsp://127.0.0.1:8560/h264/trackID=0"},
      {"rtsp://127.0.0.1:6554/h264", "", "streamid=0", "rtsp://127.0.0.1:6554/h264/streamid=0"},
      {"rtsp://c:10554/tcp/av0_0", "", "track0", "rtsp://c:10554/tcp/av0_0/track0"},
      {"rtsp://h/x", "rtsp://rtsp://turret2-cam.lan:554/stream1/", "trackID=1", "rtsp://h/x/trackID=1"},
      {"rtsp://h/x", "192.168.1.10:554/stream0/", "trackID=1", "rtsp://h/x/trackID=1"},
      {"rtsp://u:p@h/x", "", "", "rtsp://h/x"},
  };
  for (const auto& c : cases) {
    const std::string base = choose_base_url(c.content_base, "", c.request);
    EXPECT_EQ(resolve_control(base, c.control), c.expected) << c.request << " + " << c.control;
  }
}

TEST(RtspUrl, ContentLocationIsSecondChoice) {
  EXPECT_EQ(choose_base_url("", "rtsp://h/loc/", "rtsp://h/req"), "rtsp://h/loc/");
  EXPECT_EQ(choose_base_url("rtsp://h/base/", "rtsp://h/loc/", "rtsp://h/req"), "rtsp://h/base/");
}

TEST(RtspUrl, RewritesUnreachableHost) {
  EXPECT_EQ(rewrite_host("rtsp://192.168.68.111:554/live?ch=1&sub=0", "127.0.0.1", 8554),
            "rtsp://127.0.0.1:8554/live?ch=1&sub=0");
  EXPECT_EQ(rewrite_host("rtsp://u:p@10.0.0.1/x", "cam", 554), "rtsp://u:p@cam:554/x");
}

}  // namespace
}  // namespace sen3bot::camera
