#include <gtest/gtest.h>

#include "sen3bot/camera/depacketizer.hpp"

namespace sen3bot::camera {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct JpegFrames : EncodedFrameSink {
  std::vector<Bytes> frames;
  void on_frame(const EncodedFrame& f) override { frames.emplace_back(f.data.begin(), f.data.end()); }
};

// RFC 2435 main header + optional restart header + optional quantization header + scan data.
Bytes jpeg_payload(std::uint32_t offset, std::uint8_t type, std::uint8_t q, std::uint8_t w8, std::uint8_t h8,
                   const Bytes& tables, const Bytes& scan, std::uint16_t restart_interval = 0) {
  Bytes p = {0, static_cast<std::uint8_t>(offset >> 16), static_cast<std::uint8_t>(offset >> 8),
             static_cast<std::uint8_t>(offset), type, q, w8, h8};
  if (type >= 64) p.insert(p.end(), {static_cast<std::uint8_t>(restart_interval >> 8), static_cast<std::uint8_t>(restart_interval), 0xFF, 0xFF});
  if (q >= 128 && offset == 0) {
    p.insert(p.end(), {0, 0, static_cast<std::uint8_t>(tables.size() >> 8), static_cast<std::uint8_t>(tables.size())});
    p.insert(p.end(), tables.begin(), tables.end());
  }
  p.insert(p.end(), scan.begin(), scan.end());
  return p;
}

RtpPacket jpeg_packet(const Bytes& payload, std::uint32_t ts, bool marker) {
  RtpPacket p;
  p.payload = payload;
  p.timestamp = ts;
  p.marker = marker;
  return p;
}

std::size_t count_marker(const Bytes& f, std::uint8_t m) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 1 < f.size(); ++i) n += f[i] == 0xFF && f[i + 1] == m;
  return n;
}

TEST(JpegTables, Quality50IsTheAnnexKTableInZigzagOrder) {
  std::uint8_t t[128];
  make_jpeg_quant_tables(50, t);
  EXPECT_EQ(t[0], 16);
  EXPECT_EQ(t[1], 11);
  EXPECT_EQ(t[2], 12);  // zig-zag: (0,0) (0,1) (1,0)
  EXPECT_EQ(t[63], 99);
  EXPECT_EQ(t[64], 17);
  make_jpeg_quant_tables(99, t);
  EXPECT_EQ(t[0], 1);  // clamped to >= 1
}

TEST(JpegDepacketizer, BuildsJfifFromTwoFragments) {
  JpegDepacketizer d(4096);
  JpegFrames c;
  const Bytes scan1 = {1, 2, 3, 4};
  const Bytes scan2 = {5, 6};
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 160, 90, {}, scan1), 7, false), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(4, 1, 50, 160, 90, {}, scan2), 7, true), false, 0, c);
  ASSERT_EQ(c.frames.size(), 1u);
  const Bytes& f = c.frames[0];
  EXPECT_EQ(f[0], 0xFF);
  EXPECT_EQ(f[1], 0xD8);
  EXPECT_EQ(count_marker(f, 0xDB), 2u);
  EXPECT_EQ(count_marker(f, 0xC4), 4u);
  EXPECT_EQ(count_marker(f, 0xDD), 0u);
  EXPECT_EQ(f[f.size() - 2], 0xFF);
  EXPECT_EQ(f[f.size() - 1], 0xD9);
  // SOF0: height 720, width 1280, luma sampling 0x22 for type 1.
  std::size_t sof = 0;
  while (!(f[sof] == 0xFF && f[sof + 1] == 0xC0)) ++sof;
  EXPECT_EQ((f[sof + 5] << 8) | f[sof + 6], 720);
  EXPECT_EQ((f[sof + 7] << 8) | f[sof + 8], 1280);
  EXPECT_EQ(f[sof + 11], 0x22);
  EXPECT_EQ(Bytes(f.end() - 8, f.end() - 2), (Bytes{1, 2, 3, 4, 5, 6}));
}

TEST(JpegDepacketizer, InBandTablesOf64And128BytesAndRestartIntervals) {
  JpegDepacketizer d(4096);
  JpegFrames c;
  d.push(jpeg_packet(jpeg_payload(0, 65, 255, 80, 44, Bytes(64, 3), {9, 9}, 4), 1, true), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(0, 0, 255, 80, 45, Bytes(128, 4), {8}), 2, true), false, 0, c);
  ASSERT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(count_marker(c.frames[0], 0xDB), 1u);
  EXPECT_EQ(count_marker(c.frames[0], 0xDD), 1u);
  EXPECT_EQ(count_marker(c.frames[1], 0xDB), 2u);
}

TEST(JpegDepacketizer, TablesCachedForQBelow255ButNotFor255) {
  JpegDepacketizer d(4096);
  JpegFrames c;
  d.push(jpeg_packet(jpeg_payload(0, 1, 200, 8, 8, Bytes(128, 5), {1}), 1, true), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(0, 1, 200, 8, 8, {}, {1}), 2, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(c.frames[0], c.frames[1]);
  d.push(jpeg_packet(jpeg_payload(0, 1, 255, 8, 8, {}, {1}), 3, true), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(0, 1, 201, 8, 8, {}, {1}), 4, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(d.stats().malformed_packets, 2u);
}

TEST(JpegDepacketizer, OffsetGapLossAndMissingMarkerDropTheFrame) {
  JpegDepacketizer d(4096);
  JpegFrames c;
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 8, 8, {}, {1, 2}), 1, false), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(5, 1, 50, 8, 8, {}, {3}), 1, true), false, 0, c);  // expected offset 2
  EXPECT_TRUE(c.frames.empty());
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 8, 8, {}, {1, 2}), 2, false), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(2, 1, 50, 8, 8, {}, {3}), 2, true), true, 0, c);  // loss flagged
  EXPECT_TRUE(c.frames.empty());
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 8, 8, {}, {1, 2}), 3, false), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 8, 8, {}, {1, 2}), 4, true), false, 0, c);  // new timestamp
  EXPECT_EQ(c.frames.size(), 1u);
  EXPECT_GE(d.stats().frames_dropped_damaged, 2u);
}

TEST(JpegDepacketizer, RejectsReservedTypesQAndTruncation) {
  JpegDepacketizer d(4096);
  JpegFrames c;
  d.push(jpeg_packet(jpeg_payload(0, 2, 50, 8, 8, {}, {1}), 1, true), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(0, 1, 110, 8, 8, {}, {1}), 2, true), false, 0, c);
  d.push(jpeg_packet({0, 0, 0}, 3, true), false, 0, c);
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 0, 8, {}, {1}), 4, true), false, 0, c);  // width 0, no fallback
  Bytes short_tables = jpeg_payload(0, 1, 255, 8, 8, Bytes(128, 1), {});
  short_tables.resize(20);
  d.push(jpeg_packet(short_tables, 5, true), false, 0, c);
  EXPECT_TRUE(c.frames.empty());
  d.set_fallback_dimensions(2560, 1440);
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 0, 0, {}, {1}), 6, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 1u);
}

TEST(JpegDepacketizer, OversizeFrameIsDropped) {
  JpegDepacketizer d(16);
  JpegFrames c;
  d.push(jpeg_packet(jpeg_payload(0, 1, 50, 8, 8, {}, Bytes(100, 1)), 1, true), false, 0, c);
  EXPECT_TRUE(c.frames.empty());
  EXPECT_EQ(d.stats().frames_dropped_oversize, 1u);
}

}  // namespace
}  // namespace sen3bot::camera
