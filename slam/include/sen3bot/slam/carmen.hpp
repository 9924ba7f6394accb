#pragma once
// CARMEN logs (the text format of the CARMEN toolkit and the Radish data sets): their laser scans
// with the odometry pose of each, one LaserRecord at a time, for the mapper.
//
//   ODOM x y theta tv rv accel timestamp host logger_timestamp
//   FLASER n r1..rn x y theta odom_x odom_y odom_theta timestamp host logger_timestamp
//   ROBOTLASER1 type start fov resolution max_range accuracy remission_mode n r1..rn
//               m rem1..remm laser_x laser_y laser_theta robot_x robot_y robot_theta
//               tv rv forward_safety side_safety turn_axis timestamp host logger_timestamp
//
// Every other line (comments, PARAM, SYNC, RAWLASER1..4, TRUEPOS, NMEA...) is counted and skipped.
// FLASER gives no beam geometry: 180 beams are CARMEN's -90..+89 degrees at 1 degree, any other count
// spans -90..+90 (a single beam points ahead), and the maximum range is kFlaserMaxRangeM. A scan's
// laser_mount is its laser pose in the frame of its odometry (FLASER) or robot (ROBOTLASER1) pose.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/slam/laser_record.hpp"

struct gzFile_s;  // zlib's handle; the library links zlib privately, so its header stays out of here

namespace sen3bot::slam {

// FLASER carries no maximum range; the SICK scanners of the CARMEN logs reach 30 m.
inline constexpr double kFlaserMaxRangeM = 30.0;
// The longest line read (without its newline); a ROBOTLASER1 of kMaxBeams ranges and remissions
// takes about 16 KiB.
inline constexpr std::size_t kCarmenMaxLineBytes = 64 * 1024;

struct CarmenCounts {
  std::uint64_t lines = 0;
  std::uint64_t scans = 0;     // FLASER and ROBOTLASER1
  std::uint64_t odometry = 0;  // ODOM
  std::uint64_t skipped = 0;   // other line types, comments and empty lines
};

// The line grammar over text already in memory (tests, the fuzzer); the reader below feeds it a
// file. Allocates only in its constructor.
class CarmenParser {
 public:
  using Counts = CarmenCounts;

  // `source` names the text in error messages: "<source>:<line>: FLASER: ...".
  explicit CarmenParser(std::string_view source);

  // One line, without its newline. True when it was a scan, now in `out` (source_line =
  // line_number); false when it was odometry or skipped, `out` untouched. Errors (Errc::protocol)
  // name the source, the line and what is wrong; `out` may then be partly written.
  Result<bool> line(std::string_view text, std::uint64_t line_number, LaserRecord& out);

  [[nodiscard]] const Counts& counts() const noexcept { return counts_; }
  // The pose of the latest ODOM line (zero before the first).
  [[nodiscard]] const nav::Pose2D& latest_odometry() const noexcept { return latest_odometry_; }
  [[nodiscard]] std::string_view source() const noexcept { return source_; }

 private:
  std::string source_;
  Counts counts_;
  nav::Pose2D latest_odometry_;
};

// Reads a CARMEN log, plain or gzipped (zlib tells them apart by the gzip magic bytes), one scan
// at a time. Everything is allocated in open(): next() reuses one buffer and never allocates.
class CarmenReader {
 public:
  using Counts = CarmenCounts;

  // Errors (not_found, permission, io) name the path; a file zlib cannot read fails here too.
  static Result<CarmenReader> open(const std::string& path);

  // Fills `out` with the next scan; false at the end of the file. Errors name the file and the
  // 1-based line: malformed records (Errc::protocol, also for a last line cut inside its record
  // and for a line over kCarmenMaxLineBytes) and read failures (Errc::io). After an error the
  // reader stays failed and returns the same error.
  Result<bool> next(LaserRecord& out);

  [[nodiscard]] const Counts& counts() const noexcept { return parser_.counts(); }
  [[nodiscard]] const nav::Pose2D& latest_odometry() const noexcept { return parser_.latest_odometry(); }
  [[nodiscard]] std::string_view path() const noexcept { return parser_.source(); }

  CarmenReader(CarmenReader&& other) noexcept;
  CarmenReader& operator=(CarmenReader&& other) noexcept;
  CarmenReader(const CarmenReader&) = delete;
  CarmenReader& operator=(const CarmenReader&) = delete;
  ~CarmenReader();

 private:
  CarmenReader(gzFile_s* file, std::string_view path);
  // Moves the unread bytes to the front and reads more behind them; sets eof_ at the end.
  Status fill();

  gzFile_s* file_ = nullptr;
  CarmenParser parser_;
  std::unique_ptr<char[]> buffer_;  // holds at least one whole line and its newline
  std::size_t begin_ = 0;           // the unread bytes are buffer_[begin_, end_)
  std::size_t end_ = 0;
  std::uint64_t line_number_ = 0;
  bool eof_ = false;
  bool cut_ = false;  // the gzip stream ended before its end
  bool failed_ = false;
  Error error_;  // what next() returns again once failed_
};

}  // namespace sen3bot::slam
