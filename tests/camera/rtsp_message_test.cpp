#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>

#include "camera_test_util.hpp"
#include "sen3bot/camera/rtsp_message.hpp"

namespace sen3bot::camera {
namespace {

std::span<const std::uint8_t> bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(RtspMessage, ParsesResponseWithBody) {
  const std::string text = "RTSP/1.0 200 OK\r\nCseq: 7\r\nContent-Length: 4\r\nContent-Type: application/sdp\r\n\r\nv=0\nextra";
  std::size_t consumed = 0;
  auto msg = parse_message(text, &consumed);
  ASSERT_TRUE(msg.ok()) << msg.error().message();
  EXPECT_TRUE(msg->is_response);
  EXPECT_EQ(msg->status, 200);
  EXPECT_EQ(msg->cseq(), 7u);  // header names are case-insensitive (VLC sends "Cseq")
  EXPECT_EQ(msg->body, "v=0\n");
  EXPECT_EQ(consumed, text.size() - 5);
}

TEST(RtspMessage, IncompleteIsWouldBlock) {
  std::size_t consumed = 0;
  EXPECT_EQ(parse_message("RTSP/1.0 200 OK\r\nCSeq: 1\r\n", &consumed).error().code(), Errc::would_block);
  EXPECT_EQ(parse_message("RTSP/1.0 200 OK\r\nContent-Length: 10\r\n\r\nabc", &consumed).error().code(), Errc::would_block);
}

TEST(RtspMessage, HostileInputIsAProtocolError) {
  std::size_t consumed = 0;
  EXPECT_EQ(parse_message("RTSP/1.0 200 OK\r\nContent-Length: 999999999\r\n\r\n", &consumed).error().code(), Errc::protocol);
  EXPECT_EQ(parse_message("RTSP/1.0 200 OK\r\nContent-Length: -1\r\n\r\n", &consumed).error().code(), Errc::protocol);
  EXPECT_EQ(parse_message("RTSP/1.0 2x0 OK\r\n\r\n", &consumed).error().code(), Errc::protocol);
  std::string never_ends = "RTSP/1.0 200 OK\r\n";
  while (never_ends.size() < kMaxRtspHeaderBytes + 10) never_ends += "X-Pad: aaaaaaaaaaaaaaaa\r\n";
  EXPECT_EQ(parse_message(never_ends, &consumed).error().code(), Errc::protocol);
  std::string many = "RTSP/1.0 200 OK\r\n";
  for (int i = 0; i < 100; ++i) many += "X: y\r\n";
  many += "\r\n";
  EXPECT_EQ(parse_message(many, &consumed).error().code(), Errc::protocol);
}

TEST(RtspDemux, InterleavedBeforeAndBetweenResponses) {
  std::string stream;
  stream += std::string("$\x00\x00\x03" "abc", 7);
  stream += "RTSP/1.0 200 OK\r\nCSeq: 5\r\n\r\n";
  stream += std::string("$\x01\x00\x01" "z", 5);
  std::size_t pos = 0;
  std::vector<DemuxKind> kinds;
  while (pos < stream.size()) {
    auto item = demux_next(bytes(stream).subspan(pos));
    ASSERT_TRUE(item.ok());
    ASSERT_NE(item->kind, DemuxKind::need_more);
    kinds.push_back(item->kind);
    pos += item->consumed;
  }
  ASSERT_EQ(kinds.size(), 3u);
  EXPECT_EQ(kinds[0], DemuxKind::interleaved);
  EXPECT_EQ(kinds[1], DemuxKind::message);
  EXPECT_EQ(kinds[2], DemuxKind::interleaved);
}

TEST(RtspDemux, ByteByByteAndRandomChunksGiveTheSameItems) {
  std::string stream;
  for (int i = 0; i < 20; ++i) {
    stream += std::string("$\x00\x00\x05" "hello", 9);
    if (i % 5 == 0) stream += "RTSP/1.0 200 OK\r\nCSeq: " + std::to_string(i) + "\r\nSession: abc\r\n\r\n";
    if (i % 7 == 0) stream += "GET_PARAMETER rtsp://x/ RTSP/1.0\r\nCSeq: 9\r\n\r\n";
  }
  std::mt19937 rng(42);
  for (int mode = 0; mode < 2; ++mode) {
    std::string buf;
    std::size_t fed = 0;
    int frames = 0;
    int messages = 0;
    while (fed < stream.size() || !buf.empty()) {
      const std::size_t chunk = mode == 0 ? 1 : 1 + rng() % 17;
      buf += stream.substr(fed, chunk);
      fed = std::min(stream.size(), fed + chunk);
      while (true) {
        auto item = demux_next(bytes(buf));
        ASSERT_TRUE(item.ok());
        if (item->kind == DemuxKind::need_more) break;
        ASSERT_NE(item->kind, DemuxKind::garbage);
        if (item->kind == DemuxKind::interleaved) ++frames;
        if (item->kind == DemuxKind::message) ++messages;
        buf.erase(0, item->consumed);
      }
      if (fed == stream.size() && !buf.empty()) FAIL() << "left over: " << buf.size();
    }
    EXPECT_EQ(frames, 20);
    EXPECT_EQ(messages, 4 + 3);
  }
}

TEST(RtspDemux, ResynchronisesAfterGarbage) {
  const std::string stream = std::string("\x01\x02junk", 6) + std::string("$\x00\x00\x01" "q", 5);
  auto first = demux_next(bytes(stream));
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(first->kind, DemuxKind::garbage);
  auto second = demux_next(bytes(stream).subspan(first->consumed));
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(second->kind, DemuxKind::interleaved);
}

TEST(RtspDemux, ServerRequestIsAMessage) {
  const std::string text = "ANNOUNCE rtsp://h/ RTSP/1.0\r\nCSeq: 3\r\n\r\n";
  auto item = demux_next(bytes(text));
  ASSERT_TRUE(item.ok());
  ASSERT_EQ(item->kind, DemuxKind::message);
  EXPECT_FALSE(item->message.is_response);
  EXPECT_EQ(item->message.method, "ANNOUNCE");
}

TEST(RtspHeaders, Session) {
  auto s = parse_session("        708345999;timeout=60");
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->id, "708345999");
  EXPECT_EQ(s->timeout_s, 60);
  EXPECT_EQ(parse_session("cLRWwzo0+cxzua56")->timeout_s, 60);  // RFC 2326 default
  EXPECT_EQ(parse_session("8qYXB3JIx21Wt2sI;timeout=10")->timeout_s, 10);
  EXPECT_FALSE(parse_session(";timeout=5").ok());
}

TEST(RtspHeaders, TransportRepliesFromRealPeers) {
  auto gst = parse_transport("RTP/AVP/TCP;unicast;interleaved=0-1;ssrc=5C30A66E;mode=\"PLAY\"");
  ASSERT_TRUE(gst.ok());
  EXPECT_TRUE(gst->tcp);
  EXPECT_EQ(gst->rtp_channel, 0);
  EXPECT_EQ(gst->rtcp_channel, 1);
  EXPECT_EQ(gst->ssrc, 0x5C30A66Eu);
  auto vlc = parse_transport("RTP/AVP/UDP;unicast;client_port=60572-60573;server_port=51911-51912;ssrc=3CD682E9;mode=play");
  ASSERT_TRUE(vlc.ok());
  EXPECT_FALSE(vlc->tcp);
  EXPECT_EQ(vlc->server_rtp_port, 51911);
  EXPECT_EQ(vlc->server_rtcp_port, 51912);
  auto other_channels = parse_transport("RTP/AVP/TCP;unicast;interleaved=6-7");
  ASSERT_TRUE(other_channels.ok());
  EXPECT_EQ(other_channels->rtp_channel, 6);
  // Lenient SSRCs: a space and 7 digits (Hikvision), 0x (Rubetek).
  EXPECT_EQ(parse_transport("RTP/AVP/TCP;interleaved=0-1;ssrc= d6d6627")->ssrc, 0xd6d6627u);
  EXPECT_EQ(parse_transport("RTP/AVP/TCP;interleaved=0-1;ssrc=0x1A2B")->ssrc, 0x1A2Bu);
  EXPECT_FALSE(parse_transport("RTP/AVP/TCP;interleaved=0-1;ssrc=zz")->ssrc.has_value());
  EXPECT_FALSE(parse_transport("RAW/RAW/UDP;unicast").ok());
  EXPECT_FALSE(parse_transport("RTP/AVP/TCP;unicast").ok());
}

TEST(RtspHeaders, RtpInfoIsLenient) {
  auto info = parse_rtp_info("url=rtsp://h/s=0;seq=20065;rtptime=4097745679");
  EXPECT_EQ(info.seq, 20065);
  EXPECT_EQ(info.rtptime, 4097745679u);
  auto bad = parse_rtp_info("url=trackID=1;seq=1;rtptime=-1,url=x;seq=1;rtptime=-1");
  EXPECT_EQ(bad.seq, 1);
  EXPECT_FALSE(bad.rtptime.has_value());
  auto trailing = parse_rtp_info("url=rtsp://h/;seq=5;");
  EXPECT_EQ(trailing.seq, 5);
}

TEST(RtspHeaders, PublicList) {
  EXPECT_TRUE(method_listed("OPTIONS, DESCRIBE, ANNOUNCE, GET_PARAMETER, PAUSE", "GET_PARAMETER"));
  EXPECT_TRUE(method_listed("DESCRIBE,SETUP,TEARDOWN,PLAY,PAUSE,GET_PARAMETER", "GET_PARAMETER"));
  EXPECT_FALSE(method_listed("DESCRIBE SETUP PLAY STOP", "GET_PARAMETER"));
}

// Every recorded real-camera response parses, with the fields the client uses.
TEST(RtspFixtures, AllResponsesParse) {
  for (const char* name : {"anjvision_describe.txt", "bad_rtptime.txt", "bunny_describe.txt", "bunny_play.txt",
                           "bunny_setup.txt", "foscam_describe.txt", "h264dvr_describe.txt", "h264dvr_play.txt",
                           "h264dvr_setup_audio.txt", "h264dvr_setup_video.txt", "hikvision_describe.txt",
                           "hikvision_play.txt", "hikvision_setup.txt", "missing_content_type_describe.txt"}) {
    const std::string text = testing::read_fixture(std::string("rtsp/") + name);
    ASSERT_FALSE(text.empty()) << name;
    std::size_t consumed = 0;
    auto msg = parse_message(text, &consumed);
    ASSERT_TRUE(msg.ok()) << name << ": " << msg.error().message();
    EXPECT_EQ(msg->status, 200) << name;
    EXPECT_TRUE(msg->cseq().has_value()) << name;
  }
  std::size_t consumed = 0;
  const std::string hik_setup = testing::read_fixture("rtsp/hikvision_setup.txt");
  auto setup = parse_message(hik_setup, &consumed);
  ASSERT_TRUE(setup.ok());
  EXPECT_EQ(parse_session(*setup->header("Session"))->id, "708345999");
  EXPECT_EQ(parse_transport(*setup->header("Transport"))->ssrc, 0x4cacc3d1u);
}

}  // namespace
}  // namespace sen3bot::camera
