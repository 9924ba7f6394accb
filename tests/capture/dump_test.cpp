// The human-readable listing behind `sen3bot capture dump FILE`.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "capture_test_util.hpp"
#include "sen3bot/capture/dump.hpp"

namespace sen3bot::capture {
namespace {

using test::Bytes;
using ::testing::HasSubstr;
using ::testing::Not;

// Runs `print` against a temporary FILE* and returns what it wrote.
template <typename Print>
std::string capture_output(Print print) {
  std::FILE* f = std::tmpfile();
  if (f == nullptr) {
    ADD_FAILURE() << "tmpfile failed";
    return {};
  }
  print(f);
  std::fflush(f);
  std::rewind(f);
  std::string text;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
  std::fclose(f);
  return text;
}

TEST(CaptureDump, ListsHeaderChannelsAndRecords) {
  Bytes twenty(20);
  for (std::size_t i = 0; i < twenty.size(); ++i) twenty[i] = static_cast<std::uint8_t>(0xE0 + i);
  test::FileBuilder b;
  b.header(test::two_channel_info())
      .tx(hal::micros(1500), 0, Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00})
      .rx(hal::seconds(2) + 5, 1, twenty)
      .baud(hal::seconds(3), 1, 38400)
      .gap(hal::seconds(3), 2, 40)
      .end(hal::seconds(4), 3, 2);
  const auto path = test::scratch_path("dump.s3bcap");
  test::write_bytes(path, b.bytes());

  const std::string text = capture_output([&](std::FILE* out) { ASSERT_TRUE(dump(path, out)); });
  EXPECT_THAT(text, HasSubstr("format version 1"));
  EXPECT_THAT(text, HasSubstr("2024-01-01T00:00:00.000000000Z"));
  EXPECT_THAT(text, HasSubstr("1000.000000000 s"));
  EXPECT_THAT(text, HasSubstr("p2os"));
  EXPECT_THAT(text, HasSubstr("9600 baud"));
  EXPECT_THAT(text, HasSubstr("0.001500000  p2os         tx        6  fa fb 03 00 00 00\n"));
  // 20 bytes: 16 on the first line, 4 on an indented continuation line.
  EXPECT_THAT(text, HasSubstr("2.000000005  lms200       rx       20  e0 e1 e2 e3 e4 e5 e6 e7 e8 e9 ea eb ec ed ee ef\n"
                              "                                                f0 f1 f2 f3\n"));
  EXPECT_THAT(text, HasSubstr("-> 38400 baud"));
  EXPECT_THAT(text, HasSubstr("2 records (40 payload bytes) dropped here"));
  EXPECT_THAT(text, HasSubstr("3 records written, 2 dropped"));
  EXPECT_THAT(text, Not(HasSubstr("not closed cleanly")));
}

TEST(CaptureDump, SaysWhenTheCaptureWasNotClosed) {
  test::FileBuilder b;
  b.header(test::two_channel_info()).rx(1, 0, Bytes{});
  auto file = CaptureFile::parse(b.bytes());
  ASSERT_TRUE(file);
  const std::string text = capture_output([&](std::FILE* out) { ASSERT_TRUE(dump(*file, out)); });
  EXPECT_THAT(text, HasSubstr("not closed cleanly"));
}

TEST(CaptureDump, MalformedOrMissingFilePrintsNothing) {
  test::FileBuilder b;
  b.header(test::two_channel_info()).rx(5, 0, Bytes{1}).rx(4, 0, Bytes{2});
  const auto path = test::scratch_path("dump-bad.s3bcap");
  test::write_bytes(path, b.bytes());
  Status status;
  const std::string text = capture_output([&](std::FILE* out) { status = dump(path, out); });
  ASSERT_FALSE(status);
  EXPECT_THAT(std::string(status.error().message()), HasSubstr("capture offset 75"));
  EXPECT_TRUE(text.empty());

  status = dump(std::filesystem::path("/nonexistent.s3bcap"), stdout);
  ASSERT_FALSE(status);
  EXPECT_EQ(status.error().code(), Errc::not_found);
}

TEST(CaptureDump, ExtremeTimesDoNotOverflow) {
  CaptureInfo info = test::two_channel_info();
  info.start_wall_ns = INT64_MIN;  // found by the fuzzer: floor division used to overflow
  info.start_monotonic_ns = INT64_MIN;
  test::FileBuilder b;
  b.header(info).rx(INT64_MAX, 0, Bytes{1});
  auto file = CaptureFile::parse(b.bytes());
  ASSERT_TRUE(file) << file.error().c_str();
  const std::string text = capture_output([&](std::FILE* out) { ASSERT_TRUE(dump(*file, out)); });
  EXPECT_THAT(text, HasSubstr("9223372036.854775807"));
  EXPECT_THAT(text, HasSubstr("-9223372036.854775808 s"));
}

TEST(CaptureDump, DumpsTheCheckedInCapture) {
  const std::string text = capture_output(
      [&](std::FILE* out) { ASSERT_TRUE(dump(test::captures_dir() / "loopback_session.s3bcap", out)); });
  EXPECT_THAT(text, HasSubstr("lms200"));
  EXPECT_THAT(text, HasSubstr("-> 38400 baud"));
}

}  // namespace
}  // namespace sen3bot::capture
