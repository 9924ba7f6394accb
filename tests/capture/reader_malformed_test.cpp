// The reader refuses every malformed input with an Errc::protocol error naming the offset.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "capture_test_util.hpp"
#include "sen3bot/capture/reader.hpp"

namespace sen3bot::capture {
namespace {

using test::Bytes;
using test::FileBuilder;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// Header (32) + "p2os" decl (8 + 4) + "lms200" decl (8 + 6).
constexpr std::size_t kFirstRecord = 32 + 12 + 14;

FileBuilder valid_prefix() {
  FileBuilder b;
  b.header(test::two_channel_info());
  return b;
}

// Parses `bytes`, expects a protocol error at `offset` mentioning `problem`.
void expect_rejected(const Bytes& bytes, std::uint64_t offset, const std::string& problem) {
  auto file = CaptureFile::parse(bytes);
  ASSERT_FALSE(file) << "accepted; expected: " << problem;
  EXPECT_EQ(file.error().code(), Errc::protocol);
  EXPECT_THAT(std::string(file.error().message()), StartsWith("capture offset " + std::to_string(offset) + ": "));
  EXPECT_THAT(std::string(file.error().message()), HasSubstr(problem));
}

TEST(CaptureReaderRejects, EmptyInput) { expect_rejected({}, 0, "truncated file header"); }

TEST(CaptureReaderRejects, BadMagic) {
  Bytes b = valid_prefix().bytes();
  b[3] = 'X';
  expect_rejected(b, 3, "bad magic");
  expect_rejected(Bytes{'P', 'K', 3, 4}, 0, "bad magic");
  b = valid_prefix().bytes();
  b[7] = '\n' + 1;  // the CR LF pair guards against text-mode copies
  expect_rejected(b, 7, "bad magic");
}

TEST(CaptureReaderRejects, TruncatedHeader) {
  Bytes b = valid_prefix().bytes();
  b.resize(20);
  expect_rejected(b, 20, "truncated file header");
}

TEST(CaptureReaderRejects, UnknownVersion) {
  Bytes b = valid_prefix().bytes();
  le::put_u16(&b[8], 2);
  expect_rejected(b, 8, "unknown format version 2");
}

TEST(CaptureReaderRejects, TooManyChannels) {
  Bytes b = valid_prefix().bytes();
  le::put_u16(&b[10], static_cast<std::uint16_t>(kMaxChannels + 1));
  expect_rejected(b, 10, "channels declared");
}

TEST(CaptureReaderRejects, UnknownFlags) {
  Bytes b = valid_prefix().bytes();
  b[12] = 1;
  expect_rejected(b, 12, "unknown flags");
}

TEST(CaptureReaderRejects, TruncatedChannelTable) {
  Bytes b = valid_prefix().bytes();
  b.resize(32 + 5);
  expect_rejected(b, 32, "truncated channel declaration 1 of 2");
  b = valid_prefix().bytes();
  b.resize(32 + 12 + 8 + 3);  // second name cut short
  expect_rejected(b, 32 + 12 + 8, "truncated channel name");
}

TEST(CaptureReaderRejects, BadChannelDeclarations) {
  Bytes b = valid_prefix().bytes();
  b[32] = kNoChannel;
  expect_rejected(b, 32, "reserved");
  b = valid_prefix().bytes();
  b[32 + 12] = 0;  // lms200 takes p2os's id
  expect_rejected(b, 32 + 12, "declared twice");
  b = valid_prefix().bytes();
  b[33] = 0;
  expect_rejected(b, 33, "name length 0");
  b = valid_prefix().bytes();
  b[33] = static_cast<std::uint8_t>(kMaxChannelNameBytes + 1);
  expect_rejected(b, 33, "name length 33");
  b = valid_prefix().bytes();
  b[34] = 1;
  expect_rejected(b, 34, "reserved channel field");
  b = valid_prefix().bytes();
  b[32 + 8 + 2] = ' ';
  expect_rejected(b, 32 + 8 + 2, "not printable");
  b = valid_prefix().bytes();
  b[32 + 8 + 1] = 0xC3;
  expect_rejected(b, 32 + 8 + 1, "not printable");
}

TEST(CaptureReaderRejects, TruncatedRecordHeader) {
  Bytes b = valid_prefix().rx(1, 0, Bytes{1, 2}).bytes();
  b.resize(b.size() - 2 - 7);
  expect_rejected(b, kFirstRecord, "truncated record header");
}

TEST(CaptureReaderRejects, TruncatedPayload) {
  Bytes b = valid_prefix().rx(1, 0, Bytes(40, 7)).bytes();
  b.pop_back();
  expect_rejected(b, kFirstRecord, "truncated record (payload of 40 bytes, 39 left)");
}

TEST(CaptureReaderRejects, PayloadLengthOverTheBound) {
  FileBuilder fb = valid_prefix();
  fb.rx(1, 0, Bytes{1});
  Bytes b = fb.bytes();
  le::put_u32(&b[kFirstRecord + 12], static_cast<std::uint32_t>(kMaxPayloadBytes + 1));
  expect_rejected(b, kFirstRecord + 12, "payload length 65537 exceeds 65536");
  le::put_u32(&b[kFirstRecord + 12], 0xFFFFFFFFu);  // must fail on the bound, not allocate
  expect_rejected(b, kFirstRecord + 12, "exceeds");
}

TEST(CaptureReaderRejects, UnknownChannel) {
  expect_rejected(valid_prefix().rx(1, 0, Bytes{1}).tx(2, 5, Bytes{1}).bytes(), kFirstRecord + 17 + 8,
                  "unknown channel id 5");
  expect_rejected(valid_prefix().baud(1, 200, 9600).bytes(), kFirstRecord + 8, "unknown channel id 200");
}

TEST(CaptureReaderRejects, UnknownKindAndReservedBits) {
  Bytes b = valid_prefix().rx(1, 0, Bytes{1}).bytes();
  b[kFirstRecord + 9] = 9;
  expect_rejected(b, kFirstRecord + 9, "unknown record kind 9");
  b = valid_prefix().rx(1, 0, Bytes{1}).bytes();
  b[kFirstRecord + 11] = 0x80;
  expect_rejected(b, kFirstRecord + 10, "reserved record field");
}

TEST(CaptureReaderRejects, TimeGoingBackwards) {
  const Bytes b = valid_prefix().rx(1000, 0, Bytes{1}).rx(1000, 1, Bytes{2}).rx(999, 0, Bytes{3}).bytes();
  expect_rejected(b, kFirstRecord + 2 * 17, "record time 999 ns is before the previous record's 1000 ns");
  expect_rejected(valid_prefix().rx(-1, 0, Bytes{1}).bytes(), kFirstRecord, "negative record time");
}

TEST(CaptureReaderRejects, BadBaudRecords) {
  expect_rejected(valid_prefix().record(1, 1, RecordKind::baud_change, Bytes{1, 2}).bytes(), kFirstRecord + 12,
                  "baud record payload is 2 bytes");
  expect_rejected(valid_prefix().baud(1, 1, 0).bytes(), kFirstRecord + 16, "baud change to 0");
}

TEST(CaptureReaderRejects, BadGapAndEndRecords) {
  Bytes b = valid_prefix().gap(1, 1, 1).bytes();
  b[kFirstRecord + 8] = 0;
  expect_rejected(b, kFirstRecord + 8, "gap record with channel id 0");
  expect_rejected(valid_prefix().gap(1, 0, 0).bytes(), kFirstRecord + 16, "no dropped records");
  expect_rejected(valid_prefix().record(1, kNoChannel, RecordKind::gap, Bytes(8)).bytes(), kFirstRecord + 12,
                  "gap record payload is 8 bytes");
  expect_rejected(valid_prefix().record(1, kNoChannel, RecordKind::end, Bytes{}).bytes(), kFirstRecord + 12,
                  "end record payload is 0 bytes");
  expect_rejected(valid_prefix().rx(1, 0, Bytes{1}).end(1, 2, 0).bytes(), kFirstRecord + 17 + 16,
                  "end record counts 2 records, the file holds 1");
  expect_rejected(valid_prefix().gap(1, 3, 9).end(1, 0, 2).bytes(), kFirstRecord + 32 + 16 + 8,
                  "end record counts 2 dropped records, gaps hold 3");
  const FileBuilder closed = valid_prefix().rx(1, 0, Bytes{1}).end(1, 1, 0);
  FileBuilder after_end = closed;
  after_end.rx(2, 0, Bytes{1});
  expect_rejected(after_end.bytes(), closed.size(), "17 bytes after the end record");
}

TEST(CaptureReaderRejects, ErrorsAreSticky) {
  const Bytes b = valid_prefix().rx(1, 0, Bytes{1}).rx(0, 0, Bytes{1}).rx(5, 0, Bytes{1}).bytes();
  auto reader = CaptureReader::open(b);
  ASSERT_TRUE(reader);
  auto first = reader->next();
  ASSERT_TRUE(first);
  ASSERT_TRUE(first->has_value());
  auto second = reader->next();
  ASSERT_FALSE(second);
  auto third = reader->next();
  ASSERT_FALSE(third);
  EXPECT_EQ(third.error().message(), second.error().message());
}

// Every prefix of a valid capture either parses (cut exactly at a record boundary) or fails
// with a located error; none crashes or reads past the end.
TEST(CaptureReaderRejects, EveryTruncationOfAValidFile) {
  const Bytes full = valid_prefix().tx(0, 0, Bytes{0xFA, 0xFB, 3, 0, 0, 0}).rx(10, 0, Bytes{}).baud(20, 1, 38400)
                         .rx(30, 1, Bytes(100, 0x55)).gap(30, 1, 4).end(31, 4, 1).bytes();
  ASSERT_TRUE(CaptureFile::parse(full));
  std::vector<std::size_t> boundaries = {kFirstRecord};
  for (std::size_t len : {22u, 16u, 20u, 116u, 32u}) boundaries.push_back(boundaries.back() + len);
  for (std::size_t n = 0; n < full.size(); ++n) {
    auto file = CaptureFile::parse(Bytes(full.begin(), full.begin() + static_cast<long>(n)));
    const bool at_boundary = std::find(boundaries.begin(), boundaries.end(), n) != boundaries.end();
    EXPECT_EQ(file.ok(), at_boundary) << "prefix of " << n << " bytes";
    if (!file) {
      EXPECT_THAT(std::string(file.error().message()), StartsWith("capture offset ")) << n;
    }
  }
}

TEST(CaptureReaderRejects, MissingFileAndPathInMessage) {
  auto missing = CaptureFile::load("/nonexistent/capture.s3bcap");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code(), Errc::not_found);

  Bytes b = valid_prefix().bytes();
  le::put_u16(&b[8], 7);
  const auto path = test::scratch_path("bad-version.s3bcap");
  test::write_bytes(path, b);
  auto file = CaptureFile::load(path);
  ASSERT_FALSE(file);
  EXPECT_EQ(file.error().code(), Errc::protocol);
  EXPECT_THAT(std::string(file.error().message()), HasSubstr("bad-version.s3bcap: capture offset 8: unknown format version 7"));
}

}  // namespace
}  // namespace sen3bot::capture
