// `sen3bot detect`: the on-board detector on an image file, as a user checks a camera's view.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "command_capture.hpp"
#include "commands.hpp"

namespace sen3bot::firmware {
namespace {

const std::string kPhoto = "/usr/share/doc/opencv-doc/examples/data/basketball1.png";

TEST(DetectCommand, PrintsThePeopleAndDrawsThem) {
  const std::string png = "/tmp/sen3bot-detect-" + std::to_string(::getpid()) + ".png";
  const testing::CommandOutcome o =
      testing::run_command(detect_command, {"--image", kPhoto, "--repeat", "3", "--png", png});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("\"width_px\": 640, \"height_px\": 480"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"runs\": 3"), std::string::npos) << o.out;
  // One person, with a confidence.
  EXPECT_NE(o.out.find("\"people\": [{\"u0\": "), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("}, {"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"confidence\": 0."), std::string::npos) << o.out;
  struct stat st {};
  ASSERT_EQ(::stat(png.c_str(), &st), 0);
  EXPECT_GT(st.st_size, 10'000);
  std::remove(png.c_str());
}

TEST(DetectCommand, BadInputIsAClearError) {
  testing::CommandOutcome o = testing::run_command(detect_command, {});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--image is required"), std::string::npos) << o.err;
  o = testing::run_command(detect_command, {"--image", SEN3BOT_SOURCE_DIR "/README.md"});
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("cannot read it as an image"), std::string::npos) << o.err;
  o = testing::run_command(detect_command, {"--image", kPhoto, "--scale", "0.1"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("smaller than the 64x128 window"), std::string::npos) << o.err;
  o = testing::run_command(detect_command, {"--image", kPhoto, "--threshold", "high"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--threshold: expected a number"), std::string::npos) << o.err;
  o = testing::run_command(detect_command, {"--image", kPhoto, "--png", "/nonexistent/dir/out.png"});
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("cannot write /nonexistent/dir/out.png"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace sen3bot::firmware
