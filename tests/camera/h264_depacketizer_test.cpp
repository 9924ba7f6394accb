#include <gtest/gtest.h>

#include "camera_test_util.hpp"
#include "sen3bot/camera/depacketizer.hpp"

namespace sen3bot::camera {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct Collect : EncodedFrameSink {
  std::vector<Bytes> frames;
  std::vector<bool> keyframes;
  void on_frame(const EncodedFrame& f) override {
    frames.emplace_back(f.data.begin(), f.data.end());
    keyframes.push_back(f.keyframe);
  }
};

RtpPacket pkt(const Bytes& payload, std::uint32_t ts, bool marker) {
  RtpPacket p;
  p.payload = payload;
  p.timestamp = ts;
  p.marker = marker;
  return p;
}

const Bytes kSps = {0x67, 0x42, 0xC0, 0x16};
const Bytes kPps = {0x68, 0xCE, 0x3C, 0x80};
const Bytes kIdr = {0x65, 0x88, 0x84, 0x00, 0x33};
const Bytes kSlice = {0x41, 0x9A, 0x02};

Bytes annexb(std::initializer_list<Bytes> nals) {
  Bytes out;
  for (const auto& n : nals) {
    out.insert(out.end(), {0, 0, 0, 1});
    out.insert(out.end(), n.begin(), n.end());
  }
  return out;
}

TEST(H264Depacketizer, SpropInFrontOfFirstIdrThenSlices) {
  H264Depacketizer d(4096);
  d.set_parameter_sets({kSps, kPps});
  Collect c;
  d.push(pkt(kIdr, 1000, true), false, 0, c);
  d.push(pkt(kSlice, 4000, true), false, 0, c);
  ASSERT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(c.frames[0], annexb({kSps, kPps, kIdr}));
  EXPECT_TRUE(c.keyframes[0]);
  EXPECT_EQ(c.frames[1], annexb({kSlice}));
}

TEST(H264Depacketizer, StapAAndFuAReassemble) {
  H264Depacketizer d(4096);
  Collect c;
  Bytes stap = {24, 0, 4};
  stap.insert(stap.end(), kSps.begin(), kSps.end());
  stap.insert(stap.end(), {0, 4});
  stap.insert(stap.end(), kPps.begin(), kPps.end());
  d.push(pkt(stap, 10, false), false, 0, c);
  // FU-A: indicator keeps F/NRI (0x60), header carries type 5.
  d.push(pkt({0x7C, 0x85, 0x88, 0x84}, 10, false), false, 0, c);
  d.push(pkt({0x7C, 0x05, 0x00}, 10, false), false, 0, c);
  d.push(pkt({0x7C, 0x45, 0x33}, 10, true), false, 0, c);
  ASSERT_EQ(c.frames.size(), 1u);
  EXPECT_EQ(c.frames[0], annexb({kSps, kPps, kIdr}));  // in-band parameter sets: no sprop added
}

TEST(H264Depacketizer, NonCompliantFuAForms) {
  H264Depacketizer d(4096);
  d.set_parameter_sets({kSps, kPps});
  Collect c;
  // S and E in one packet, with the reserved bit set (retina#131, #109).
  d.push(pkt({0x7C, 0xE5, 0x88, 0x84, 0x00, 0x33}, 10, true), false, 0, c);
  ASSERT_EQ(c.frames.size(), 1u);
  EXPECT_EQ(c.frames[0], annexb({kSps, kPps, kIdr}));
  // A tail without a start (joined mid-NAL) is dropped, never appended.
  d.push(pkt({0x7C, 0x41, 0x9A, 0x02}, 20, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 1u);
  EXPECT_EQ(d.stats().fragments_dropped, 1u);
}

TEST(H264Depacketizer, TimestampChangeEndsAnAccessUnitWithoutMarker) {
  H264Depacketizer d(4096);
  d.set_parameter_sets({kSps, kPps});
  Collect c;
  d.push(pkt(kIdr, 100, false), false, 0, c);
  d.push(pkt(kSlice, 200, false), false, 0, c);
  ASSERT_EQ(c.frames.size(), 1u);
  d.push(pkt(kSlice, 200, true), false, 0, c);
  ASSERT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(c.frames[1], annexb({kSlice, kSlice}));
}

TEST(H264Depacketizer, WaitsForIdrAtStartAndAfterLoss) {
  H264Depacketizer d(4096);
  d.set_parameter_sets({kSps, kPps});
  Collect c;
  d.push(pkt(kSlice, 1, true), false, 0, c);  // joined mid-GOP
  EXPECT_EQ(c.frames.size(), 0u);
  EXPECT_EQ(d.stats().frames_dropped_no_idr, 1u);
  d.push(pkt(kIdr, 2, true), false, 0, c);
  d.push(pkt(kSlice, 3, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 2u);
  // A loss: slices are dropped until the next IDR.
  d.push(pkt(kSlice, 5, true), true, 0, c);
  d.push(pkt(kSlice, 6, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 2u);
  d.push(pkt(kIdr, 7, true), false, 0, c);
  EXPECT_EQ(c.frames.size(), 3u);
  EXPECT_TRUE(c.keyframes[2]);
}

TEST(H264Depacketizer, LossInsideAnAccessUnitDropsIt) {
  H264Depacketizer d(4096);
  d.set_parameter_sets({kSps, kPps});
  Collect c;
  d.push(pkt({0x7C, 0x85, 0x88}, 10, false), false, 0, c);
  d.push(pkt({0x7C, 0x45, 0x33}, 10, true), true, 0, c);
  EXPECT_EQ(c.frames.size(), 0u);
  EXPECT_EQ(d.stats().frames_dropped_damaged, 1u);
}

TEST(H264Depacketizer, MalformedStapAAndOversizeAreCounted) {
  H264Depacketizer d(64);
  d.set_parameter_sets({kSps, kPps});
  Collect c;
  d.push(pkt({24, 0, 50, 0x65}, 1, true), false, 0, c);
  EXPECT_EQ(d.stats().malformed_packets, 1u);
  d.push(pkt({24, 0, 0}, 2, true), false, 0, c);
  EXPECT_EQ(d.stats().malformed_packets, 2u);
  Bytes big(100, 0x11);
  big[0] = 0x65;
  d.push(pkt(big, 3, true), false, 0, c);
  EXPECT_EQ(d.stats().frames_dropped_oversize, 1u);
  d.push(pkt({25, 1, 2}, 4, true), false, 0, c);
  EXPECT_EQ(d.stats().unsupported_packets, 1u);
  EXPECT_TRUE(c.frames.empty());
}

}  // namespace
}  // namespace sen3bot::camera
