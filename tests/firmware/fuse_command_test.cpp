// `sen3bot fuse`: boxes fused offline with the scans of a recorded LMS200 session, and the box
// file's and the command line's errors.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "command_capture.hpp"
#include "commands.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/lms200/capture_decode.hpp"

namespace sen3bot::firmware {
namespace {

const std::string kCapture = SEN3BOT_SOURCE_DIR "/tests/data/captures/lms200_session.s3bcap";

std::string write_boxes(const std::string& text) {
  const std::string path = "/tmp/sen3bot-boxes-" + std::to_string(::getpid()) + ".jsonl";
  std::ofstream(path) << text;
  return path;
}

double number_after(const std::string& text, const std::string& key, std::size_t from = 0) {
  const std::size_t at = text.find("\"" + key + "\": ", from);
  return at == std::string::npos ? std::nan("") : std::strtod(text.c_str() + at + key.size() + 4, nullptr);
}

// The recorded session's scans, as the command reads them.
std::vector<lms200::CapturedScan> scans_with_ranges(std::vector<std::vector<float>>& keep) {
  Result<capture::CaptureFile> file = capture::CaptureFile::load(kCapture);
  EXPECT_TRUE(file);
  std::vector<lms200::CapturedScan> scans;
  if (!file) return scans;
  EXPECT_TRUE(lms200::for_each_scan(*file, "", [&](const lms200::CapturedScan& s) {
    keep.emplace_back(s.ranges_m.begin(), s.ranges_m.end());
    scans.push_back(s);
  }));
  for (std::size_t i = 0; i < scans.size(); ++i) scans[i].ranges_m = keep[i];
  return scans;
}

TEST(FuseCommand, ABoxAheadPlacesWhatTheLaserSawThere) {
  std::vector<std::vector<float>> keep;
  const std::vector<lms200::CapturedScan> scans = scans_with_ranges(keep);
  ASSERT_GE(scans.size(), 2u);
  const lms200::CapturedScan& first = scans.front();
  ASSERT_EQ(first.ranges_m.size(), 361u);
  EXPECT_NEAR(first.increment_rad, 0.5 * 3.14159265358979 / 180.0, 1e-9);
  // The nearest return within the box's bearings (about +-2 degrees ahead).
  double nearest = 1e9;
  for (std::size_t i = 176; i <= 184; ++i) nearest = std::min(nearest, static_cast<double>(first.ranges_m[i]));
  ASSERT_LT(nearest, 79.0);
  char line[256];
  std::snprintf(line, sizeof line,
                "# a box straight ahead, a box of another class, and a frame long after the recording\n"
                "{\"t_s\": %.6f, \"boxes\": [[700, 0, 760, 719, 0.9, 0], [100, 0, 150, 719, 0.9, 2]]}\n"
                "{\"t_s\": 500.0, \"boxes\": [[700, 0, 760, 719, 0.9, 0]]}\n",
                first.t_s);
  const std::string boxes = write_boxes(line);
  testing::CommandOutcome o = testing::run_command(fuse_command, {"--capture", kCapture, "--boxes", boxes});
  ASSERT_EQ(o.code, 0) << o.err;
  const std::size_t second_line = o.out.find('\n') + 1;
  const double x = number_after(o.out, "x_m");
  const double y = number_after(o.out, "y_m");
  EXPECT_NEAR(std::atan2(y, x), 0.0, 0.05) << o.out;  // ahead
  EXPECT_GE(std::hypot(x, y), nearest - 0.01) << o.out;
  EXPECT_LE(std::hypot(x, y), nearest + 0.3) << o.out;  // at most the body's depth behind it
  EXPECT_NE(o.out.find("\"boxes\": {\"located\": 1, \"other_class\": 1}"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\"people\": [], \"boxes\": {\"out_of_window\": 1}", second_line), std::string::npos) << o.out;
  EXPECT_NE(o.err.find("2 frames, 1 people placed"), std::string::npos) << o.err;

  // From a laser at (10, 5) facing +y, the same person is 'ahead' along +y.
  const testing::CommandOutcome moved =
      testing::run_command(fuse_command, {"--capture", kCapture, "--boxes", boxes, "--pose", "10,5,90"});
  ASSERT_EQ(moved.code, 0) << moved.err;
  EXPECT_NEAR(number_after(moved.out, "x_m"), 10.0 - y, 0.002) << moved.out;
  EXPECT_NEAR(number_after(moved.out, "y_m"), 5.0 + x, 0.002) << moved.out;
  std::remove(boxes.c_str());
}

TEST(FuseCommand, BadInputIsAClearError) {
  const std::string good = write_boxes("{\"t_s\": 1.0, \"boxes\": []}\n");
  testing::CommandOutcome o = testing::run_command(fuse_command, {"--capture", kCapture});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--capture and --boxes are required"), std::string::npos) << o.err;
  o = testing::run_command(fuse_command, {"--capture", kCapture, "--boxes", good, "--pose", "1,2"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("--pose: expected X,Y,THETA_DEG"), std::string::npos) << o.err;
  o = testing::run_command(fuse_command, {"--capture", kCapture, "--boxes", good, "--window", "-1"});
  EXPECT_EQ(o.code, 2);
  o = testing::run_command(fuse_command,
                           {"--capture", SEN3BOT_SOURCE_DIR "/tests/data/captures/p2os_session.s3bcap", "--boxes", good});
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("no LMS200 channel"), std::string::npos) << o.err;
  o = testing::run_command(fuse_command, {"--capture", "/nonexistent.s3bcap", "--boxes", good});
  EXPECT_EQ(o.code, 1);
  std::remove(good.c_str());

  const struct {
    const char* text;
    const char* error;
  } bad[] = {
      {"{\"t_s\": 1.0}\n", ":1: expected {\"t_s\": T, \"boxes\": [...]}"},
      {"\n# ok\n{\"t_s\": 1.0, \"boxes\": [[1, 2, 3]]}\n", ":3: a box is [u0, v0, u1, v1, confidence, class]"},
      {"{\"t_s\": 1.0, \"boxes\": [[5, 2, 3, 4, 0.5, 0]]}\n", ":1: a box needs 0 <= u0 <= u1"},
      {"{\"t_s\": 1.0, \"boxes\": [[1, 2, 3, 4, 1.5, 0]]}\n", ":1: a box needs"},
      {"{\"t_s\": .nan, \"boxes\": []}\n", ":1: t_s must be a finite time"},
      {"{\"t_s\": 1.0, \"boxes\": [[1, 2, 3\n", ":1: yaml-cpp"},
      {"{\"t_s\": \"soon\", \"boxes\": []}\n", ":1: yaml-cpp"},
  };
  for (const auto& b : bad) {
    const std::string path = write_boxes(b.text);
    o = testing::run_command(fuse_command, {"--capture", kCapture, "--boxes", path});
    EXPECT_EQ(o.code, 2) << b.text;
    EXPECT_NE(o.err.find(path + b.error), std::string::npos) << b.text << " -> " << o.err;
    std::remove(path.c_str());
  }
  std::string many = "{\"t_s\": 1.0, \"boxes\": [";
  for (int i = 0; i < 17; ++i) many += std::string(i ? ", " : "") + "[1, 2, 3, 4, 0.5, 0]";
  const std::string path = write_boxes(many + "]}\n");
  o = testing::run_command(fuse_command, {"--capture", kCapture, "--boxes", path});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find(":1: 17 boxes, at most 16 a frame"), std::string::npos) << o.err;
  std::remove(path.c_str());
}

}  // namespace
}  // namespace sen3bot::firmware
