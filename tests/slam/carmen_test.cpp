#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/slam/carmen.hpp"

namespace sen3bot::slam {
namespace {

constexpr double kCarmenPi = std::numbers::pi;
constexpr double kCarmenDegree = kCarmenPi / 180.0;

// A FLASER line of n ranges 1.0, 1.5, 2.0, ...: laser pose and odometry pose, timestamp `t`.
std::string flaser_line(int n, const std::string& laser, const std::string& odom, const std::string& t) {
  std::string s = "FLASER " + std::to_string(n);
  for (int i = 0; i < n; ++i) s += " " + std::to_string(1.0 + 0.5 * (i % 20));
  return s + " " + laser + " " + odom + " " + t + " nohost " + t;
}

// Runs a parser over `text` and returns the scans (the error, if any, in `error`).
struct CarmenRun {
  std::vector<LaserRecord> scans;
  CarmenCounts counts;
  std::string error;
};

CarmenRun carmen_parse(std::string_view text) {
  CarmenRun p;
  CarmenParser parser("t.log");
  auto record = std::make_unique<LaserRecord>();
  std::uint64_t line = 0;
  while (!text.empty()) {
    const std::size_t eol = text.find('\n');
    const std::string_view one = text.substr(0, eol);
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    Result<bool> r = parser.line(one, ++line, *record);
    if (!r.ok()) {
      p.error = r.error().c_str();
      break;
    }
    if (*r) p.scans.push_back(*record);
  }
  p.counts = parser.counts();
  return p;
}

// A fresh directory under the system's temporary one, removed with the fixture.
class CarmenFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir[] = "/tmp/sen3bot_carmen_XXXXXX";
    ASSERT_NE(::mkdtemp(dir), nullptr);
    dir_ = dir;
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, std::string_view bytes) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return path;
  }
  std::string write_gzip(const std::string& name, std::string_view bytes) const {
    const std::string path = (dir_ / name).string();
    gzFile out = gzopen(path.c_str(), "wb");
    EXPECT_NE(out, nullptr);
    EXPECT_EQ(gzwrite(out, bytes.data(), static_cast<unsigned>(bytes.size())),
              static_cast<int>(bytes.size()));
    EXPECT_EQ(gzclose(out), Z_OK);
    return path;
  }
  std::filesystem::path dir_;
};

// Reads a whole file: its scans, counts and the error that ended it ("" at a clean end).
CarmenRun carmen_read(const std::string& path) {
  CarmenRun p;
  Result<CarmenReader> reader = CarmenReader::open(path);
  if (!reader.ok()) {
    p.error = reader.error().c_str();
    return p;
  }
  auto record = std::make_unique<LaserRecord>();
  for (;;) {
    Result<bool> r = reader->next(*record);
    if (!r.ok()) {
      p.error = r.error().c_str();
      break;
    }
    if (!*r) break;
    p.scans.push_back(*record);
  }
  p.counts = reader->counts();
  return p;
}

const std::string kOdomLine = "ODOM 1.5 -2.25 0.5 0.1 0.2 0 12.5 host 12.75";
// A SICK LMS: 181 beams from -90 degrees at 1 degree, 81.9 m maximum, 0.25 m ahead of the robot
// and turned by 0.1 rad; the robot at (2, 3) facing +90 degrees.
std::string robotlaser_line() {
  std::string s = "ROBOTLASER1 0 -1.5707963 3.1415926 0.0174533 81.9 0.01 0 181";
  for (int i = 0; i < 181; ++i) s += i == 5 ? " 81.9" : " 2.5";
  s += " 2 0.5 0.25";                // two remissions
  s += " 2.0 3.25 1.6707963";        // laser pose (robot pose + 0.25 forward, + 0.1 rad)
  s += " 2.0 3.0 1.5707963";         // robot pose
  s += " 0.3 0.05 0.4 0.2 1000000";  // tv rv safety distances turn axis
  return s + " 42.5 pioneer 42.625";
}

TEST(Carmen, ReadsEachLineType) {
  const std::string text = "# a comment\n"
                           "PARAM robot_front_laser_max 81.9 nohost 0\n"
                           "\n"
                           "SYNC 1 nohost 2\n" +
                           kOdomLine + "\n" +
                           "RAWLASER1 0 -1.57 3.14 0.017 81.9 0.01 0 2 1 1 0 1.0 host 1.0\n" +
                           flaser_line(180, "1 2 0.5", "1 2 0.5", "13.0") + "\n" +
                           "TRUEPOS 1 2 3 4 5 6 7 host 7\n"
                           "NMEAGGA 1 2 3\n" +
                           robotlaser_line() + "\n" +
                           "SOMETHINGNEW 1 2\n";
  const CarmenRun p = carmen_parse(text);
  ASSERT_EQ(p.error, "");
  ASSERT_EQ(p.scans.size(), 2u);
  EXPECT_EQ(p.counts.lines, 11u);
  EXPECT_EQ(p.counts.scans, 2u);
  EXPECT_EQ(p.counts.odometry, 1u);
  EXPECT_EQ(p.counts.skipped, 8u);

  const LaserRecord& f = p.scans[0];
  EXPECT_EQ(f.source_line, 7u);
  EXPECT_EQ(f.count, 180u);
  EXPECT_DOUBLE_EQ(f.time_s, 13.0);
  EXPECT_EQ(f.odometry, (nav::Pose2D{1.0, 2.0, 0.5}));
  EXPECT_NEAR(f.laser_mount.x_m, 0.0, 1e-12);
  EXPECT_NEAR(f.laser_mount.y_m, 0.0, 1e-12);
  EXPECT_NEAR(f.laser_mount.theta_rad, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(f.max_range_m, 30.0);
  EXPECT_FLOAT_EQ(f.ranges[0], 1.0f);
  EXPECT_FLOAT_EQ(f.ranges[1], 1.5f);
  EXPECT_FLOAT_EQ(f.ranges[179], 1.0f + 0.5f * 19.0f);

  const LaserRecord& r = p.scans[1];
  EXPECT_EQ(r.source_line, 10u);
  EXPECT_EQ(r.count, 181u);
  EXPECT_DOUBLE_EQ(r.time_s, 42.5);
  EXPECT_DOUBLE_EQ(r.start_angle_rad, -1.5707963);
  EXPECT_DOUBLE_EQ(r.angle_increment_rad, 0.0174533);
  EXPECT_DOUBLE_EQ(r.max_range_m, 81.9);
  EXPECT_EQ(r.odometry, (nav::Pose2D{2.0, 3.0, 1.5707963}));
  // The laser pose in the robot's frame (the log's angles have 7 decimals).
  EXPECT_NEAR(r.laser_mount.x_m, 0.25, 1e-7);
  EXPECT_NEAR(r.laser_mount.y_m, 0.0, 1e-7);
  EXPECT_NEAR(r.laser_mount.theta_rad, 0.1, 1e-7);
  EXPECT_FLOAT_EQ(r.ranges[0], 2.5f);
  EXPECT_FLOAT_EQ(r.ranges[5], 81.9f);  // at the maximum: kept, the mapper drops it
  EXPECT_FLOAT_EQ(r.ranges[180], 2.5f);
}

TEST(Carmen, RemembersTheLatestOdometry) {
  CarmenParser parser("t.log");
  auto record = std::make_unique<LaserRecord>();
  record->count = 7;
  Result<bool> r = parser.line(kOdomLine, 1, *record);
  ASSERT_TRUE(r.ok()) << r.error().c_str();
  EXPECT_FALSE(*r);
  EXPECT_EQ(record->count, 7u);  // untouched by a line that is not a scan
  EXPECT_EQ(parser.latest_odometry(), (nav::Pose2D{1.5, -2.25, 0.5}));
  r = parser.line("ODOM +3 4e-1 -0.25 0 0 0 13 host 13\r", 2, *record);  // '+', exponent, CRLF
  ASSERT_TRUE(r.ok()) << r.error().c_str();
  EXPECT_EQ(parser.latest_odometry(), (nav::Pose2D{3.0, 0.4, -0.25}));
  EXPECT_EQ(parser.counts().odometry, 2u);
}

TEST(Carmen, FlaserBeamGeometry) {
  struct Case {
    int n;
    double increment;
  } cases[] = {
      {180, 1.0 * kCarmenDegree},  // CARMEN: -90 .. +89
      {181, 1.0 * kCarmenDegree},  // -90 .. +90
      {361, 0.5 * kCarmenDegree},  // -90 .. +90
      {91, 2.0 * kCarmenDegree},   // any other count spans the half circle too
  };
  for (const Case& c : cases) {
    const CarmenRun p = carmen_parse(flaser_line(c.n, "0 0 0", "0 0 0", "1"));
    ASSERT_EQ(p.error, "") << c.n;
    ASSERT_EQ(p.scans.size(), 1u);
    const LaserRecord& s = p.scans[0];
    EXPECT_EQ(s.count, static_cast<std::uint32_t>(c.n));
    EXPECT_DOUBLE_EQ(s.start_angle_rad, -90.0 * kCarmenDegree) << c.n;
    EXPECT_NEAR(s.angle_increment_rad, c.increment, 1e-15) << c.n;
  }
  const LaserRecord last180 = carmen_parse(flaser_line(180, "0 0 0", "0 0 0", "1")).scans.at(0);
  EXPECT_NEAR(last180.start_angle_rad + 179 * last180.angle_increment_rad, 89.0 * kCarmenDegree, 1e-12);
  const LaserRecord last181 = carmen_parse(flaser_line(181, "0 0 0", "0 0 0", "1")).scans.at(0);
  EXPECT_NEAR(last181.start_angle_rad + 180 * last181.angle_increment_rad, 90.0 * kCarmenDegree, 1e-12);
}

TEST(Carmen, FlaserMountIsRelativeToOdometry) {
  // Odometry at (1, 1) facing +90 degrees; the laser 0.2 m ahead of it, i.e. at (1, 1.2).
  const CarmenRun p =
      carmen_parse(flaser_line(180, "1 1.2 1.5707963267948966", "1 1 1.5707963267948966", "5"));
  ASSERT_EQ(p.error, "");
  const LaserRecord& s = p.scans.at(0);
  EXPECT_NEAR(s.laser_mount.x_m, 0.2, 1e-12);
  EXPECT_NEAR(s.laser_mount.y_m, 0.0, 1e-12);
  EXPECT_NEAR(s.laser_mount.theta_rad, 0.0, 1e-12);
  EXPECT_EQ(s.odometry, (nav::Pose2D{1.0, 1.0, kCarmenPi / 2.0}));
}

TEST(Carmen, KeepsZeroAndMaximumReadings) {
  const CarmenRun p = carmen_parse("FLASER 4 0 30 45.5 0.0 0 0 0 0 0 0 1 h 1");
  ASSERT_EQ(p.error, "");
  const LaserRecord& s = p.scans.at(0);
  EXPECT_EQ(s.count, 4u);
  EXPECT_FLOAT_EQ(s.ranges[0], 0.0f);
  EXPECT_FLOAT_EQ(s.ranges[1], 30.0f);
  EXPECT_FLOAT_EQ(s.ranges[2], 45.5f);
}

TEST(Carmen, ReportsMalformedLinesWithTheirNumber) {
  const std::string ok180 = flaser_line(180, "0 0 0", "0 0 0", "1");
  struct Case {
    std::string line;
    const char* expect;
  } cases[] = {
      {"FLASER 3 1 2 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: 3 ranges announced, 2 found"},
      {"FLASER 3 1 2 3 4 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: 3 ranges announced, 4 found"},
      {"FLASER 3 1 2 3", "t.log:2: FLASER: 3 ranges announced, then 9 more fields expected: 3 fields found"},
      {"FLASER 0 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range count is 0, less than 1"},
      {"FLASER 1082 1", "t.log:2: FLASER: range count '1082' is more than 1081"},
      {"FLASER 99999999999999999999999 1",
       "t.log:2: FLASER: range count '99999999999999999999999' is more than"},
      {"FLASER 99999999999999999999999x 1",
       "t.log:2: FLASER: range count '99999999999999999999999x' is not a whole"},
      {"FLASER -3 1 2 3", "t.log:2: FLASER: range count '-3' is not a whole number"},
      {"FLASER 3.0 1 2 3", "t.log:2: FLASER: range count '3.0' is not a whole number"},
      {"FLASER", "t.log:2: FLASER: range count missing"},
      {"FLASER 2 1 x 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range 2 of 2 'x' is not a number"},
      {"FLASER 2 1 -0.5 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range 2 of 2 '-0.5' is negative"},
      {"FLASER 2 nan 1 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range 1 of 2 'nan' is not a finite number"},
      {"FLASER 2 1 inf 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range 2 of 2 'inf' is not a finite number"},
      {"FLASER 2 1 1e300 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range 2 of 2 '1e300' is out of range"},
      {"FLASER 2 1 1,5 0 0 0 0 0 0 1 h 1", "t.log:2: FLASER: range 2 of 2 '1,5' is not a number"},
      {"FLASER 2 1 1 0 0 0 0 0 zz 1 h 1", "t.log:2: FLASER: odom_theta 'zz' is not a number"},
      {"FLASER 2 1 1 0 0 0 0 0 0 1 h 1x", "t.log:2: FLASER: logger_timestamp '1x' is not a number"},
      {"FLASER 2 1 1 0 0 0 0 0 0 1e999 h 1", "t.log:2: FLASER: timestamp '1e999' is out of range"},
      {"FLASER 2 1 1 0 0 0 0 0 0 1e999x h 1", "t.log:2: FLASER: timestamp '1e999x' is not a number"},
      {"FLASER 1 1 1e308 0 0 -1e308 0 0 1 h 1", "t.log:2: FLASER: laser pose too far from the odometry pose"},
      {"ODOM 1 2", "t.log:2: ODOM: theta missing"},
      {"ODOM 1 2 3 0 0 0 5 host", "t.log:2: ODOM: logger_timestamp missing"},
      {"ODOM 1 2 3 0 0 0 5 host 5 extra", "t.log:2: ODOM: trailing text 'extra' after the record"},
      {"ODOM 1 2 nan 0 0 0 5 host 5", "t.log:2: ODOM: theta 'nan' is not a finite number"},
      {"ODOM 1 2 0x10 0 0 0 5 host 5", "t.log:2: ODOM: theta '0x10' is not a number"},
      {"ODOM 1 +-2 3 0 0 0 5 host 5", "t.log:2: ODOM: y '+-2' is not a number"},
      {"ROBOTLASER1 0 -1.57 3.14 0.0174 0 0.01 0 1 1 0 0 0 0 0 0 0 0 0 0 0 0 1 h 1",
       "t.log:2: ROBOTLASER1: maximum_range 0 is not above 0"},
      {"ROBOTLASER1 0 -1.57 3.14 0.0174 80 0.01 0 2 1", "t.log:2: ROBOTLASER1: 2 ranges announced, 1 found"},
      {"ROBOTLASER1 0 -1.57 3.14 0.0174 80 0.01 0 1 1 3 0.5", "t.log:2: ROBOTLASER1: remission missing"},
      {"ROBOTLASER1 0 -1.57 3.14 0.0174 80 0.01 0 1 1 0 0 0 0 0 0 0 0 0 0 0 0 1 h",
       "t.log:2: ROBOTLASER1: logger_timestamp missing"},
      {"ROBOTLASER1 0 -1.57 3.14 0.0174 80 0.01 0 1 1 0 0 0 0 0 0 0 0 0 0 0 0 1 h 1 2",
       "t.log:2: ROBOTLASER1: trailing text '2' after the record"},
      {"ROBOTLASER1 0 -1.57 3.14 0.0174 80 0.01 0 1 1 2000 1",
       "t.log:2: ROBOTLASER1: remission count '2000' is more"},
  };
  for (const Case& c : cases) {
    const CarmenRun p = carmen_parse(ok180 + "\n" + c.line + "\n" + ok180 + "\n");
    EXPECT_EQ(p.error.rfind(c.expect, 0), 0u)
        << c.line << "\n  gave: " << p.error << "\n  wanted: " << c.expect;
    EXPECT_EQ(p.scans.size(), 1u) << c.line;
  }
}

TEST(Carmen, QuotesOnlyTheStartOfALongField) {
  const CarmenRun p = carmen_parse("ODOM 1 2 " + std::string(500, '7') + "x 0 0 0 5 host 5");
  EXPECT_EQ(p.error, "t.log:1: ODOM: theta '777777777777777777777777' is not a number");
}

TEST_F(CarmenFiles, ReportsErrorsWithTheFileAndLine) {
  const std::string path =
      write("bad.log",
            "# header\n" + kOdomLine + "\n" + flaser_line(180, "0 0 0", "0 0 0", "1") + "\nFLASER 180 1 2\n");
  Result<CarmenReader> reader = CarmenReader::open(path);
  ASSERT_TRUE(reader.ok()) << reader.error().c_str();
  auto record = std::make_unique<LaserRecord>();
  Result<bool> r = reader->next(*record);
  ASSERT_TRUE(r.ok() && *r);
  EXPECT_EQ(record->source_line, 3u);
  r = reader->next(*record);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code(), Errc::protocol);
  const std::string expect =
      path + ":4: FLASER: 180 ranges announced, then 9 more fields expected: 2 fields found";
  EXPECT_EQ(std::string(r.error().message()), expect);
  // The reader stays failed.
  r = reader->next(*record);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(std::string(r.error().message()), expect);
  EXPECT_EQ(reader->counts().lines, 4u);
}

TEST_F(CarmenFiles, TruncatedFileIsAnErrorAtThatLine) {
  const std::string whole = kOdomLine + "\n" + flaser_line(180, "0 0 0", "0 0 0", "1") + "\n" + kOdomLine +
                            "\n" + flaser_line(180, "0 0 0", "0 0 0", "2") + "\n";
  // Cut inside the last scan's ranges, then just before its last field, then inside its keyword.
  const std::size_t last = whole.rfind("FLASER");
  for (const std::size_t cut : {last + 300, whole.size() - 3, last + 3}) {
    const CarmenRun p = carmen_read(write("cut.log", whole.substr(0, cut)));
    EXPECT_EQ(p.scans.size(), 1u);
    EXPECT_NE(p.error.find("cut.log:4: "), std::string::npos) << p.error;
    EXPECT_NE(p.error.find("the file is cut"), std::string::npos) << p.error;
  }
  // A whole last record without its newline is no error.
  const CarmenRun p = carmen_read(write("whole.log", whole.substr(0, whole.size() - 1)));
  EXPECT_EQ(p.error, "");
  EXPECT_EQ(p.scans.size(), 2u);
  EXPECT_EQ(p.counts.lines, 4u);
}

TEST_F(CarmenFiles, GzippedFileEqualsPlain) {
  std::string text = "# written by the test\r\n";
  for (int i = 0; i < 400; ++i) {
    const std::string t = std::to_string(i);
    text += "ODOM " + t + " 0 0.1 0 0 0 " + t + " h " + t + "\n";
    text += flaser_line(i % 2 == 0 ? 180 : 361, "0 0 0", t + " 0 0.1", t) + "\n";  // ~600 KB: several fills
  }
  const CarmenRun plain = carmen_read(write("plain.log", text));
  const CarmenRun gzipped = carmen_read(write_gzip("packed.log.gz", text));
  ASSERT_EQ(plain.error, "");
  ASSERT_EQ(gzipped.error, "");
  ASSERT_EQ(plain.scans.size(), 400u);
  ASSERT_EQ(gzipped.scans.size(), plain.scans.size());
  for (std::size_t i = 0; i < plain.scans.size(); ++i) {
    const LaserRecord& a = plain.scans[i];
    const LaserRecord& b = gzipped.scans[i];
    ASSERT_EQ(a.source_line, b.source_line);
    ASSERT_EQ(a.count, b.count);
    ASSERT_EQ(a.odometry, b.odometry);
    ASSERT_EQ(a.time_s, b.time_s);
    ASSERT_EQ(a.angle_increment_rad, b.angle_increment_rad);
    ASSERT_TRUE(std::equal(a.ranges.begin(), a.ranges.begin() + a.count, b.ranges.begin())) << i;
  }
  EXPECT_EQ(plain.scans.back().source_line, 801u);
  EXPECT_EQ(gzipped.counts.lines, 801u);
  EXPECT_EQ(gzipped.counts.odometry, 400u);
  EXPECT_EQ(gzipped.counts.skipped, 1u);
}

TEST_F(CarmenFiles, CutGzipStreamIsAnError) {
  std::string text;
  for (int i = 0; i < 50; ++i) text += flaser_line(180, "0 0 0", "0 0 0", std::to_string(i)) + "\n";
  const std::string packed = write_gzip("whole.gz", text);
  std::ifstream in(packed, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const CarmenRun p = carmen_read(write("cut.gz", std::string_view(bytes).substr(0, bytes.size() / 2)));
  EXPECT_NE(p.error.find("the file is cut"), std::string::npos) << p.error;
  EXPECT_LT(p.scans.size(), 50u);
}

TEST_F(CarmenFiles, LineLongerThanTheBufferIsAnError) {
  const std::string line = flaser_line(180, "0 0 0", "0 0 0", "1") + "\n";
  const std::string text = line + "# " + std::string(kCarmenMaxLineBytes + 10, 'x') + "\n" + line;
  const CarmenRun p = carmen_read(write("long.log", text));
  EXPECT_EQ(p.scans.size(), 1u);
  EXPECT_NE(p.error.find("long.log:2: line longer than 65536 bytes"), std::string::npos) << p.error;
  // One just within the limit is read.
  const std::string fits = line + "# " + std::string(kCarmenMaxLineBytes - 2, 'x') + "\n" + line;
  const CarmenRun q = carmen_read(write("fits.log", fits));
  EXPECT_EQ(q.error, "");
  EXPECT_EQ(q.scans.size(), 2u);
}

TEST_F(CarmenFiles, OpenErrorsNameThePath) {
  const std::string missing = (dir_ / "missing.log").string();
  Result<CarmenReader> reader = CarmenReader::open(missing);
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.error().code(), Errc::not_found);
  EXPECT_NE(std::string(reader.error().message()).find(missing), std::string::npos) << reader.error().c_str();

  reader = CarmenReader::open(dir_.string());  // a directory opens but cannot be read
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.error().code(), Errc::io);
  EXPECT_NE(std::string(reader.error().message()).find(dir_.string()), std::string::npos);

  const CarmenRun empty = carmen_read(write("empty.log", ""));
  EXPECT_EQ(empty.error, "");
  EXPECT_EQ(empty.counts.lines, 0u);
}

TEST_F(CarmenFiles, ReaderMoves) {
  const std::string path = write("two.log", flaser_line(180, "0 0 0", "0 0 0", "1") + "\n" +
                                                flaser_line(180, "0 0 0", "0 0 0", "2") + "\n");
  Result<CarmenReader> opened = CarmenReader::open(path);
  ASSERT_TRUE(opened.ok());
  auto record = std::make_unique<LaserRecord>();
  CarmenReader a = std::move(*opened);
  ASSERT_TRUE(*a.next(*record));
  CarmenReader b = std::move(a);
  ASSERT_TRUE(*b.next(*record));
  EXPECT_DOUBLE_EQ(record->time_s, 2.0);
  Result<bool> end = b.next(*record);
  ASSERT_TRUE(end.ok());
  EXPECT_FALSE(*end);
  EXPECT_EQ(b.counts().scans, 2u);
  EXPECT_EQ(b.path(), path);
}

TEST(Carmen, ReadsTheIntelLog) {
  const std::filesystem::path path =
      std::filesystem::path(SEN3BOT_SOURCE_DIR) / ".." / "shared" / "datasets" / "slam" / "intel-raw.log.gz";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no Intel log at " << path.string();
  Result<CarmenReader> reader = CarmenReader::open(path.string());
  ASSERT_TRUE(reader.ok()) << reader.error().c_str();
  auto record = std::make_unique<LaserRecord>();
  // open() allocates everything: not even the first next() may.
  std::uint64_t scans = 0;
  std::uint64_t other_counts = 0;
  LaserRecord first_scan_head;  // the first scan's fields, checked after the count
  bool ok = true;
  mem::testing::AllocationScope scope;
  for (;;) {
    Result<bool> r = reader->next(*record);
    if (!r.ok()) {
      ok = false;
      break;
    }
    if (!*r) break;
    if (++scans == 1) {
      first_scan_head.source_line = record->source_line;
      first_scan_head.count = record->count;
      first_scan_head.ranges[0] = record->ranges[0];
      first_scan_head.start_angle_rad = record->start_angle_rad;
      first_scan_head.angle_increment_rad = record->angle_increment_rad;
    }
    if (record->count != 180u) ++other_counts;
  }
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  EXPECT_EQ(allocations, 0u);
  if (mem::testing::counts_malloc()) {
    EXPECT_EQ(malloc_calls, 0u);
  }
  EXPECT_EQ(first_scan_head.source_line, 2u);
  EXPECT_EQ(first_scan_head.count, 180u);
  EXPECT_FLOAT_EQ(first_scan_head.ranges[0], 1.07f);
  EXPECT_DOUBLE_EQ(first_scan_head.start_angle_rad, -kCarmenPi / 2.0);
  EXPECT_DOUBLE_EQ(first_scan_head.angle_increment_rad, kCarmenDegree);
  Result<bool> last = reader->next(*record);  // failed: the error again; done: false again
  ASSERT_TRUE(ok) << (last.ok() ? "" : last.error().c_str());
  ASSERT_FALSE(*last);
  EXPECT_EQ(scans, 2726u);
  EXPECT_EQ(other_counts, 0u);
  EXPECT_EQ(reader->counts().scans, 2726u);
  EXPECT_EQ(reader->counts().odometry, 2726u);
  EXPECT_EQ(reader->counts().skipped, 0u);
  EXPECT_EQ(reader->counts().lines, 2 * 2726u);
  EXPECT_DOUBLE_EQ(record->time_s, 2725.0);
  EXPECT_EQ(record->laser_mount, (nav::Pose2D{}));
}

}  // namespace
}  // namespace sen3bot::slam
