#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "camera_test_util.hpp"
#include "sen3bot/camera/rtp.hpp"

namespace sen3bot::camera {
namespace {

using testing::rtp_packet;

TEST(Rtp, ParsesHeaderCsrcExtensionPadding) {
  auto p = rtp_packet(0xFFFF, 0xDEADBEEF, true, 96, {1, 2, 3});
  auto r = parse_rtp(p);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->marker);
  EXPECT_EQ(r->payload_type, 96);
  EXPECT_EQ(r->sequence, 0xFFFF);
  EXPECT_EQ(r->timestamp, 0xDEADBEEFu);
  EXPECT_EQ(r->payload.size(), 3u);

  // CC=1, X=1 with a 1-word extension, P=1 with 2 padding bytes.
  std::vector<std::uint8_t> q = {0xB1, 96, 0, 1, 0, 0, 0, 0, 0, 0, 0, 1, 9, 9, 9, 9,
                                 0xBE, 0xDE, 0, 1, 7, 7, 7, 7, 0xAA, 0xBB, 0, 2};
  auto s = parse_rtp(q);
  ASSERT_TRUE(s.ok()) << s.error().message();
  ASSERT_EQ(s->payload.size(), 2u);
  EXPECT_EQ(s->payload[0], 0xAA);
}

TEST(Rtp, RejectsTruncatedAndInvalid) {
  EXPECT_FALSE(parse_rtp(std::vector<std::uint8_t>(11, 0x80)).ok());
  auto v1 = rtp_packet(1, 1, false, 96, {1});
  v1[0] = 0x40;
  EXPECT_FALSE(parse_rtp(v1).ok());
  auto csrc = rtp_packet(1, 1, false, 96, {1});
  csrc[0] = 0x8F;  // 15 CSRCs, none present
  EXPECT_FALSE(parse_rtp(csrc).ok());
  auto ext = rtp_packet(1, 1, false, 96, {0xBE, 0xDE, 0xFF, 0xFF});
  ext[0] = 0x90;
  EXPECT_FALSE(parse_rtp(ext).ok());
  auto pad = rtp_packet(1, 1, false, 96, {1, 2, 200});
  pad[0] = 0xA0;
  EXPECT_FALSE(parse_rtp(pad).ok());
}

TEST(SequenceTracker, WrapsAndCountsLoss) {
  SequenceTracker t;
  std::uint64_t ext = 0;
  std::uint16_t seq = 65530;
  for (int i = 0; i < 20; ++i, ++seq) {
    if (i == 8 || i == 9) continue;  // two lost across the wrap
    ASSERT_EQ(t.update(seq, ext), SequenceTracker::Verdict::accept);
  }
  EXPECT_EQ(t.max_extended(), (1ull << 16) | 13u);
  EXPECT_EQ(t.lost(), 2u);
  EXPECT_EQ(t.update(static_cast<std::uint16_t>(seq - 1), ext), SequenceTracker::Verdict::duplicate_or_late);
}

TEST(SequenceTracker, LargeJumpNeedsTwoInARowToRestart) {
  SequenceTracker t;
  std::uint64_t ext = 0;
  ASSERT_EQ(t.update(100, ext), SequenceTracker::Verdict::accept);
  EXPECT_EQ(t.update(40000, ext), SequenceTracker::Verdict::probation);
  EXPECT_EQ(t.update(40001, ext), SequenceTracker::Verdict::restart);
  EXPECT_EQ(t.update(40002, ext), SequenceTracker::Verdict::accept);
}

TEST(ReorderBuffer, ShuffledDuplicatedStreamComesOutInOrder) {
  std::vector<std::uint64_t> order;
  for (std::uint64_t s = 1000; s < 1200; ++s) order.push_back(s);
  std::mt19937 rng(7);
  // The first packet arrives first: it is released at once, as nothing says to wait.
  for (std::size_t i = 1; i + 4 < order.size(); i += 4) std::shuffle(order.begin() + i, order.begin() + i + 4, rng);
  std::vector<std::uint64_t> with_dups;
  for (std::size_t i = 0; i < order.size(); ++i) {
    with_dups.push_back(order[i]);
    if (i % 13 == 0) with_dups.push_back(order[i]);
  }
  ReorderBuffer buf(8, 64);
  std::vector<std::uint64_t> out;
  std::uint64_t lost = 0;
  ReorderBuffer::Released r;
  for (std::uint64_t s : with_dups) {
    const std::uint8_t b[1] = {static_cast<std::uint8_t>(s)};
    auto res = buf.push(s, b);
    while (res == ReorderBuffer::PushResult::ahead) {
      ASSERT_TRUE(buf.pop(r, true));
      out.push_back(r.extended_seq);
      res = buf.push(s, b);
    }
    while (buf.pop(r)) {
      out.push_back(r.extended_seq);
      lost += r.lost_before;
    }
  }
  while (buf.pop(r, true)) out.push_back(r.extended_seq);
  ASSERT_EQ(out.size(), 200u);
  EXPECT_TRUE(std::is_sorted(out.begin(), out.end()));
  EXPECT_EQ(lost, 0u);
}

TEST(ReorderBuffer, HoleIsSkippedWhenFullAndLateIsDropped) {
  ReorderBuffer buf(4, 16);
  const std::uint8_t b[1] = {0};
  ReorderBuffer::Released r;
  ASSERT_EQ(buf.push(10, b), ReorderBuffer::PushResult::stored);
  ASSERT_TRUE(buf.pop(r));
  for (std::uint64_t s : {12, 13, 14}) ASSERT_EQ(buf.push(s, b), ReorderBuffer::PushResult::stored);
  EXPECT_FALSE(buf.pop(r));  // 11 may still come
  ASSERT_EQ(buf.push(15, b), ReorderBuffer::PushResult::ahead);
  ASSERT_TRUE(buf.pop(r, true));  // give up on the hole at 11
  EXPECT_EQ(r.extended_seq, 12u);
  EXPECT_EQ(r.lost_before, 1u);
  EXPECT_EQ(buf.push(11, b), ReorderBuffer::PushResult::late);
  ASSERT_EQ(buf.push(15, b), ReorderBuffer::PushResult::stored);
  EXPECT_EQ(buf.push(13, b), ReorderBuffer::PushResult::duplicate);
  std::vector<std::uint8_t> big(17);
  EXPECT_EQ(buf.push(16, big), ReorderBuffer::PushResult::too_big);
}

TEST(Rtcp, ReceiverReportLayout) {
  std::uint8_t out[128];
  ReceiverReportInputs in;
  in.our_ssrc = 0x01020304;
  in.source_ssrc = 0xAABBCCDD;
  in.have_source = true;
  in.cumulative_lost = 5;
  in.extended_highest_seq = 0x10005;
  const std::size_t n = build_receiver_report(in, out);
  ASSERT_GT(n, 0u);
  EXPECT_EQ(n % 4, 0u);
  EXPECT_EQ(out[0], 0x81);
  EXPECT_EQ(out[1], 201);
  EXPECT_EQ(out[3], 7);  // 32 bytes = 8 words - 1
  EXPECT_EQ(out[32 + 1], 202);
  EXPECT_EQ(build_receiver_report(in, std::span<std::uint8_t>(out, 10)), 0u);
}

}  // namespace
}  // namespace sen3bot::camera
