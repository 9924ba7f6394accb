#include <gtest/gtest.h>

#include "camera_test_util.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/camera/sdp.hpp"

namespace sen3bot::camera {
namespace {

std::string body_of(const std::string& fixture) {
  const std::string text = testing::read_fixture("rtsp/" + fixture);
  const std::size_t split = text.find("\r\n\r\n");
  return split == std::string::npos ? text : text.substr(split + 4);
}

TEST(Sdp, GStreamerH264) {
  const char* sdp =
      "v=0\r\no=- 1 1 IN IP4 127.0.0.1\r\ns=x\r\nt=0 0\r\na=control:*\r\nm=video 0 RTP/AVP 96\r\n"
      "a=rtpmap:96 H264/90000\r\n"
      "a=fmtp:96 packetization-mode=1;sprop-parameter-sets=Z0LAFtoCgL/lwFqDAwNSgAAAAwCAAAAPR4sXUA==,aM48gA==;"
      "profile-level-id=42c016;level-asymmetry-allowed=1\r\na=control:stream=0\r\n";
  auto sd = parse_sdp(sdp);
  ASSERT_TRUE(sd.ok()) << sd.error().message();
  EXPECT_EQ(sd->session_control, "*");
  const SdpMedia* v = sd->first_supported_video();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->codec, VideoCodec::h264);
  EXPECT_EQ(v->payload_type, 96);
  EXPECT_EQ(v->clock_rate_hz, 90000u);
  EXPECT_EQ(v->control, "stream=0");
  EXPECT_EQ(v->packetization_mode, 1);
  ASSERT_EQ(v->parameter_sets.size(), 2u);
  EXPECT_EQ(v->parameter_sets[0][0] & 0x1F, 7);
  EXPECT_EQ(v->parameter_sets[1][0] & 0x1F, 8);
}

TEST(Sdp, StaticJpegWithoutRtpmapAndSpacesInFmtp) {
  auto jpeg = parse_sdp("v=0\nm=video 0 RTP/AVP 26\nb=AS:200\na=control:streamid=0\n");
  ASSERT_TRUE(jpeg.ok());
  ASSERT_NE(jpeg->first_supported_video(), nullptr);
  EXPECT_EQ(jpeg->first_supported_video()->codec, VideoCodec::jpeg);
  EXPECT_TRUE(jpeg->session_control.empty());
  auto ff = parse_sdp(
      "v=0\nm=video 0 RTP/AVP 96\na=rtpmap:96 H264/90000\n"
      "a=fmtp:96 packetization-mode=1; sprop-parameter-sets=Z0LAFtoCgL/lwEQAAAMABAAAAwB6PFi6gA==,aM4PyA==; profile-level-id=42C016\n");
  ASSERT_TRUE(ff.ok());
  EXPECT_EQ(ff->first_supported_video()->parameter_sets.size(), 2u);
}

TEST(Sdp, BadSpropIsIgnoredNotFatal) {
  auto sd = parse_sdp("v=0\nm=video 0 RTP/AVP 96\na=rtpmap:96 H264/90000\na=fmtp:96 sprop-parameter-sets=!!!,aM4PyA==\n");
  ASSERT_TRUE(sd.ok());
  EXPECT_EQ(sd->first_supported_video()->parameter_sets.size(), 1u);
}

TEST(Sdp, MalformedIsAnError) {
  EXPECT_FALSE(parse_sdp("").ok());
  EXPECT_FALSE(parse_sdp("garbage").ok());
  EXPECT_FALSE(parse_sdp(std::string(kMaxSdpBytes + 1, 'v')).ok());
  std::string many = "v=0\n";
  for (int i = 0; i < 40; ++i) many += "m=video 0 RTP/AVP 96\n";
  EXPECT_FALSE(parse_sdp(many).ok());
  EXPECT_FALSE(parse_sdp("v=0\nm=video\n").ok());
}

TEST(Sdp, H265IsNotSupportedVideo) {
  for (const std::string& text : {body_of("anjvision_describe.txt"), testing::read_fixture("rtsp/tplink_sdp.txt")}) {
    auto sd = parse_sdp(text);
    ASSERT_TRUE(sd.ok());
    EXPECT_EQ(sd->first_supported_video(), nullptr);
    const Error why = no_supported_video(*sd);
    EXPECT_EQ(why.code(), Errc::not_supported);
    EXPECT_EQ(why.message(), "the camera offers only H265 video (rtpmap H265/90000); supported: H264, JPEG");
  }
}

TEST(Sdp, NoSupportedVideoSaysWhatIsOffered) {
  auto reason = [](const char* text) {
    auto sd = parse_sdp(text);
    EXPECT_TRUE(sd.ok());
    EXPECT_EQ(sd->first_supported_video(), nullptr) << text;
    return std::string(no_supported_video(*sd).message());
  };
  EXPECT_EQ(reason("v=0\nm=audio 0 RTP/AVP 0\na=rtpmap:0 PCMU/8000\nm=application 0 RTP/AVP 107\n"),
            "the SDP has no video track (media: audio PCMU/8000, application)");
  EXPECT_EQ(reason("v=0\ns=x\n"), "the SDP has no media at all (no m= line)");
  // Two unsupported tracks, one without rtpmap; a codec offered twice is named once.
  EXPECT_EQ(reason("v=0\nm=video 0 RTP/AVP 96\na=rtpmap:96 H265/90000\nm=video 0 RTP/AVP 97\n"
                   "m=video 0 RTP/AVP 98\na=rtpmap:98 H265/90000\n"),
            "the camera offers only H265, unknown video (rtpmap H265/90000; payload type 97 without rtpmap; "
            "rtpmap H265/90000); supported: H264, JPEG");
  EXPECT_EQ(reason("v=0\nm=video 0 RTP/AVP 96\na=rtpmap:96 H2650/90000\nm=video 0 RTP/AVP 97\na=rtpmap:97 H265/90000\n"),
            "the camera offers only H2650, H265 video (rtpmap H2650/90000; rtpmap H265/90000); supported: H264, JPEG");
}

TEST(Sdp, HikvisionSkipsMetadataTrack) {
  auto sd = parse_sdp(body_of("hikvision_describe.txt"));
  ASSERT_TRUE(sd.ok()) << sd.error().message();
  ASSERT_EQ(sd->media.size(), 2u);
  const SdpMedia* v = sd->first_supported_video();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->width_px, 1920);
  EXPECT_EQ(v->height_px, 1080);
  EXPECT_EQ(v->control, "rtsp://192.168.5.106:554/Streaming/Channels/101/trackID=1?transportmode=unicast&profile=Profile_1");
  EXPECT_EQ(sd->media[1].codec, VideoCodec::unknown);
}

TEST(Sdp, EveryRecordedDescriptionHasAVideoTrack) {
  for (const char* name : {"bunny_describe.txt", "foscam_describe.txt", "h264dvr_describe.txt",
                           "hikvision_describe.txt", "missing_content_type_describe.txt", "anpviz_sdp.txt",
                           "geovision_sdp.txt", "ubiquiti_sdp.txt"}) {
    const std::string text = testing::read_fixture(std::string("rtsp/") + name);
    const std::string body = text.starts_with("v=0") ? text : body_of(name);
    auto sd = parse_sdp(body);
    ASSERT_TRUE(sd.ok()) << name << ": " << sd.error().message();
    const SdpMedia* v = sd->first_supported_video();
    ASSERT_NE(v, nullptr) << name;
    EXPECT_EQ(v->codec, VideoCodec::h264) << name;
    EXPECT_FALSE(v->parameter_sets.empty()) << name;
  }
}

}  // namespace
}  // namespace sen3bot::camera
