// `sen3bot cobot tags`: the printable tags of an operator, read back as the robot reads them.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "command_capture.hpp"
#include "commands.hpp"
#include "sen3bot/cobot/qr_reader.hpp"

namespace sen3bot::firmware {
namespace {

msg::TagFrame read_png(const std::string& path) {
  const cv::Mat page = cv::imread(path, cv::IMREAD_GRAYSCALE);
  msg::TagFrame out;
  if (page.empty()) return out;
  cobot::QrReader reader;
  if (!reader.init(static_cast<std::uint32_t>(page.cols), static_cast<std::uint32_t>(page.rows)).ok()) return out;
  camera::FrameRef ref;
  ref.data = page.data;
  ref.width_px = static_cast<std::uint32_t>(page.cols);
  ref.height_px = static_cast<std::uint32_t>(page.rows);
  ref.stride_bytes = static_cast<std::uint32_t>(page.step[0]);
  ref.format = camera::PixelFormat::gray8;
  reader.read(ref, out);
  return out;
}

TEST(CobotCommand, WritesBothTagsOfAnOperator) {
  const std::string dir = "/tmp/sen3bot-tags-" + std::to_string(::getpid());
  const testing::CommandOutcome o =
      testing::run_command(cobot_command, {"tags", "--operator", "42", "--out", dir, "--module-px", "6"});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("operator-42-front.png: operator 42 FRONT, payload S3B1:F:000042:"), std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("operator-42-back.png: operator 42 BACK, payload S3B1:B:000042:"), std::string::npos) << o.out;
  for (const auto& [name, side] : {std::pair{"front", msg::TagSide::front}, std::pair{"back", msg::TagSide::back}}) {
    const std::string path = dir + "/operator-42-" + name + ".png";
    const msg::TagFrame read = read_png(path);
    ASSERT_EQ(read.count, 1u) << path;
    EXPECT_EQ(read.tags[0].operator_id, 42u);
    EXPECT_EQ(read.tags[0].side, side);
    std::remove(path.c_str());
  }
  ::rmdir(dir.c_str());
}

TEST(CobotCommand, BadArgumentsAreClearErrors) {
  testing::CommandOutcome o = testing::run_command(cobot_command, {});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("usage: sen3bot cobot tags"), std::string::npos) << o.err;
  o = testing::run_command(cobot_command, {"tags", "--out", "/tmp"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--operator and --out are required"), std::string::npos) << o.err;
  for (const char* id : {"0", "1000000", "x", "-3"}) {
    o = testing::run_command(cobot_command, {"tags", "--operator", id, "--out", "/tmp"});
    EXPECT_EQ(o.code, 2) << id;
    EXPECT_NE(o.err.find("--operator: expected 1..999999"), std::string::npos) << o.err;
  }
  o = testing::run_command(cobot_command, {"tags", "--operator", "1", "--out", "/tmp", "--module-px", "1"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--module-px: expected 2..200"), std::string::npos) << o.err;
  o = testing::run_command(cobot_command, {"tags", "--operator", "1", "--out", "/tmp", "--colour", "red"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("unknown or incomplete option '--colour'"), std::string::npos) << o.err;
  o = testing::run_command(cobot_command, {"tags", "--operator", "1", "--out", "/nonexistent/dir/tags"});
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("cannot create /nonexistent/dir/tags"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace sen3bot::firmware
