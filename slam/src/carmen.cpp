// The CARMEN log reader. A line is split into fields on blanks and read left to right; numbers go
// through std::from_chars (locale-independent). The file is read through zlib in large blocks into
// one buffer of twice the longest line, and lines are cut from it in place, so next() neither
// copies a line nor allocates. gzread rather than gzgets: it reports how many bytes it gave, so a
// NUL inside a line cannot hide the rest of it, and a cut last line is told from a whole one.
#include "sen3bot/slam/carmen.hpp"

#include <zlib.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <utility>

namespace sen3bot::slam {
namespace {

constexpr std::size_t kBufferBytes = 2 * kCarmenMaxLineBytes;
// The fields of a FLASER after its ranges: two poses, timestamp, host, logger timestamp.
constexpr std::size_t kFlaserTail = 9;

bool is_blank(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// The blank-separated fields of one line, taken in order.
class Fields {
 public:
  explicit Fields(std::string_view text) noexcept : rest_(text) {}

  bool next(std::string_view& field) noexcept {
    std::size_t i = 0;
    while (i < rest_.size() && is_blank(rest_[i])) ++i;
    std::size_t j = i;
    while (j < rest_.size() && !is_blank(rest_[j])) ++j;
    field = rest_.substr(i, j - i);
    rest_.remove_prefix(j);
    return !field.empty();
  }

  [[nodiscard]] std::size_t count() const noexcept {
    Fields copy(rest_);
    std::size_t n = 0;
    for (std::string_view field; copy.next(field);) ++n;
    return n;
  }

 private:
  std::string_view rest_;
};

// Where a message points: "<source>:<line>: <keyword>: ...".
struct Context {
  std::string_view source;
  std::uint64_t line;
  const char* keyword;
};

[[gnu::format(printf, 2, 3)]] Error fail(const Context& c, const char* fmt, ...) noexcept {
  char what[Error::kMessageCapacity];
  std::va_list args;
  va_start(args, fmt);
  std::vsnprintf(what, sizeof what, fmt, args);
  va_end(args);
  return Error::format(Errc::protocol, "%.*s:%llu: %s: %s", static_cast<int>(c.source.size()),
                       c.source.data(), static_cast<unsigned long long>(c.line), c.keyword, what);
}

// A field as quoted in a message: binary junk and long tokens must not fill it.
int shown(std::string_view field) noexcept { return static_cast<int>(field.size() < 24 ? field.size() : 24); }

enum class Parsed { ok, not_number, out_of_range, not_finite };

Parsed parse_double(std::string_view field, double& out) noexcept {
  // from_chars takes no leading '+', which some writers put on positive numbers.
  if (field.size() > 1 && field.front() == '+' && field[1] != '-') field.remove_prefix(1);
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, out);
  if ((ec != std::errc() && ec != std::errc::result_out_of_range) || ptr != end) return Parsed::not_number;
  if (ec == std::errc::result_out_of_range) return Parsed::out_of_range;
  if (!std::isfinite(out)) return Parsed::not_finite;  // from_chars reads "nan" and "inf"
  return Parsed::ok;
}

// The next field as a finite number; `name` says which one in messages.
Status read_number(Fields& fields, const Context& c, const char* name, double& out) noexcept {
  std::string_view field;
  if (!fields.next(field)) return fail(c, "%s missing", name);
  switch (parse_double(field, out)) {
    case Parsed::ok:
      return {};
    case Parsed::not_number:
      return fail(c, "%s '%.*s' is not a number", name, shown(field), field.data());
    case Parsed::out_of_range:
      return fail(c, "%s '%.*s' is out of range", name, shown(field), field.data());
    case Parsed::not_finite:
      break;
  }
  return fail(c, "%s '%.*s' is not a finite number", name, shown(field), field.data());
}

// The next field as a whole count in [low, high].
Status read_count(Fields& fields, const Context& c, const char* name, std::uint32_t low, std::uint32_t high,
                  std::uint32_t& out) noexcept {
  std::string_view field;
  if (!fields.next(field)) return fail(c, "%s missing", name);
  std::uint64_t value = 0;
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, value);
  if ((ec != std::errc() && ec != std::errc::result_out_of_range) || ptr != end) {
    return fail(c, "%s '%.*s' is not a whole number", name, shown(field), field.data());
  }
  if (ec == std::errc::result_out_of_range || value > high) {
    return fail(c, "%s '%.*s' is more than %u", name, shown(field), field.data(), high);
  }
  if (value < low) {
    return fail(c, "%s is %llu, less than %u", name, static_cast<unsigned long long>(value), low);
  }
  out = static_cast<std::uint32_t>(value);
  return {};
}

// A range reading, 1-based `index` of `count`: a finite number >= 0 that fits a float. Zero and
// readings past the maximum stay as given: the mapper takes them as no return.
Status read_range(Fields& fields, const Context& c, std::uint32_t index, std::uint32_t count,
                  float& out) noexcept {
  std::string_view field;
  if (!fields.next(field)) return fail(c, "%u ranges announced, %u found", count, index - 1);
  double value = 0.0;
  switch (parse_double(field, value)) {
    case Parsed::ok:
      break;
    case Parsed::not_number:
      return fail(c, "range %u of %u '%.*s' is not a number", index, count, shown(field), field.data());
    case Parsed::out_of_range:
    case Parsed::not_finite:
      return fail(c, "range %u of %u '%.*s' is not a finite number", index, count, shown(field),
                  field.data());
  }
  if (value < 0.0) {
    return fail(c, "range %u of %u '%.*s' is negative", index, count, shown(field), field.data());
  }
  if (value > static_cast<double>(std::numeric_limits<float>::max())) {
    return fail(c, "range %u of %u '%.*s' is out of range", index, count, shown(field), field.data());
  }
  out = static_cast<float>(value);
  return {};
}

Status read_pose(Fields& fields, const Context& c, const char* const (&names)[3], nav::Pose2D& out) noexcept {
  if (Status s = read_number(fields, c, names[0], out.x_m); !s) return s;
  if (Status s = read_number(fields, c, names[1], out.y_m); !s) return s;
  return read_number(fields, c, names[2], out.theta_rad);
}

// Two far-apart poses (1e308 and -1e308) are each finite, their difference is not.
bool finite(const nav::Pose2D& p) noexcept {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}

// "timestamp host logger_timestamp", the end of every CARMEN record, then nothing more.
Status read_tail(Fields& fields, const Context& c, double& timestamp) noexcept {
  if (Status s = read_number(fields, c, "timestamp", timestamp); !s) return s;
  std::string_view field;
  if (!fields.next(field)) return fail(c, "host missing");
  double logger_timestamp = 0.0;
  if (Status s = read_number(fields, c, "logger_timestamp", logger_timestamp); !s) return s;
  if (fields.next(field)) return fail(c, "trailing text '%.*s' after the record", shown(field), field.data());
  return {};
}

Status parse_odom(Fields& fields, const Context& c, nav::Pose2D& pose) noexcept {
  if (Status s = read_pose(fields, c, {"x", "y", "theta"}, pose); !s) return s;
  double ignored = 0.0;
  for (const char* name : {"tv", "rv", "accel"}) {
    if (Status s = read_number(fields, c, name, ignored); !s) return s;
  }
  return read_tail(fields, c, ignored);
}

// FLASER: the field count is checked first, so a short or long range list is reported as such
// rather than as a pose field that does not parse.
Status parse_flaser(Fields& fields, const Context& c, LaserRecord& out) noexcept {
  std::uint32_t n = 0;
  if (Status s = read_count(fields, c, "range count", 1, kMaxBeams, n); !s) return s;
  const std::size_t after = fields.count();
  if (after < n + kFlaserTail && after >= kFlaserTail) {
    return fail(c, "%u ranges announced, %zu found", n, after - kFlaserTail);
  }
  if (after < kFlaserTail) {
    return fail(c, "%u ranges announced, then %zu more fields expected: %zu fields found", n, kFlaserTail,
                after);
  }
  if (after > n + kFlaserTail) {
    return fail(c, "%u ranges announced, %zu found (or trailing text)", n, after - kFlaserTail);
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    if (Status s = read_range(fields, c, i + 1, n, out.ranges[i]); !s) return s;
  }
  nav::Pose2D laser;
  nav::Pose2D odometry;
  if (Status s = read_pose(fields, c, {"x", "y", "theta"}, laser); !s) return s;
  if (Status s = read_pose(fields, c, {"odom_x", "odom_y", "odom_theta"}, odometry); !s) return s;
  if (Status s = read_tail(fields, c, out.time_s); !s) return s;
  out.laser_mount = nav::relative_pose(odometry, laser);
  if (!finite(out.laser_mount)) return fail(c, "laser pose too far from the odometry pose");
  out.count = n;
  out.odometry = odometry;
  out.max_range_m = kFlaserMaxRangeM;
  // CARMEN's geometry: 180 beams are -90..+89 at 1 degree, every other count spans -90..+90.
  constexpr double kPi = std::numbers::pi;
  out.start_angle_rad = n == 1 ? 0.0 : -kPi / 2.0;
  out.angle_increment_rad = n == 180 ? kPi / 180.0 : n == 1 ? 0.0 : kPi / static_cast<double>(n - 1);
  return {};
}

Status parse_robotlaser(Fields& fields, const Context& c, LaserRecord& out) noexcept {
  double ignored = 0.0;
  double start = 0.0;
  double resolution = 0.0;
  double max_range = 0.0;
  if (Status s = read_number(fields, c, "laser_type", ignored); !s) return s;
  if (Status s = read_number(fields, c, "start_angle", start); !s) return s;
  if (Status s = read_number(fields, c, "field_of_view", ignored); !s) return s;
  if (Status s = read_number(fields, c, "angular_resolution", resolution); !s) return s;
  if (Status s = read_number(fields, c, "maximum_range", max_range); !s) return s;
  if (max_range <= 0.0) return fail(c, "maximum_range %g is not above 0", max_range);
  if (Status s = read_number(fields, c, "accuracy", ignored); !s) return s;
  if (Status s = read_number(fields, c, "remission_mode", ignored); !s) return s;
  std::uint32_t n = 0;
  if (Status s = read_count(fields, c, "range count", 1, kMaxBeams, n); !s) return s;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (Status s = read_range(fields, c, i + 1, n, out.ranges[i]); !s) return s;
  }
  std::uint32_t m = 0;
  if (Status s = read_count(fields, c, "remission count", 0, kMaxBeams, m); !s) return s;
  for (std::uint32_t i = 0; i < m; ++i) {
    if (Status s = read_number(fields, c, "remission", ignored); !s) return s;
  }
  nav::Pose2D laser;
  nav::Pose2D robot;
  if (Status s = read_pose(fields, c, {"laser_x", "laser_y", "laser_theta"}, laser); !s) return s;
  if (Status s = read_pose(fields, c, {"robot_x", "robot_y", "robot_theta"}, robot); !s) return s;
  for (const char* name : {"laser_tv", "laser_rv", "forward_safety_dist", "side_safety_dist", "turn_axis"}) {
    if (Status s = read_number(fields, c, name, ignored); !s) return s;
  }
  if (Status s = read_tail(fields, c, out.time_s); !s) return s;
  out.laser_mount = nav::relative_pose(robot, laser);
  if (!finite(out.laser_mount)) return fail(c, "laser pose too far from the robot pose");
  out.count = n;
  out.odometry = robot;
  out.max_range_m = max_range;
  out.start_angle_rad = start;
  out.angle_increment_rad = resolution;
  return {};
}

// A last line without its newline whose keyword is cut short ("FLA") would otherwise be skipped
// as an unknown line type.
bool cut_keyword(std::string_view text) noexcept {
  Fields fields(text);
  std::string_view keyword;
  if (!fields.next(keyword) || fields.next(keyword)) return false;
  for (std::string_view known : {"ODOM", "FLASER", "ROBOTLASER1"}) {
    if (keyword.size() < known.size() && known.substr(0, keyword.size()) == keyword) return true;
  }
  return false;
}

}  // namespace

CarmenParser::CarmenParser(std::string_view source) : source_(source) {}

Result<bool> CarmenParser::line(std::string_view text, std::uint64_t line_number, LaserRecord& out) {
  ++counts_.lines;
  Fields fields(text);
  std::string_view keyword;
  if (!fields.next(keyword) || keyword.front() == '#') {
    ++counts_.skipped;
    return false;
  }
  if (keyword == "ODOM") {
    nav::Pose2D pose;
    if (Status s = parse_odom(fields, {source_, line_number, "ODOM"}, pose); !s) return s.error();
    latest_odometry_ = pose;
    ++counts_.odometry;
    return false;
  }
  Status parsed;
  if (keyword == "FLASER") {
    parsed = parse_flaser(fields, {source_, line_number, "FLASER"}, out);
  } else if (keyword == "ROBOTLASER1") {
    parsed = parse_robotlaser(fields, {source_, line_number, "ROBOTLASER1"}, out);
  } else {
    ++counts_.skipped;  // RAWLASER1..4 (no pose), PARAM, SYNC, TRUEPOS, NMEA..., unknown types
    return false;
  }
  if (!parsed) return parsed.error();
  out.source_line = line_number;
  ++counts_.scans;
  return true;
}

CarmenReader::CarmenReader(gzFile_s* file, std::string_view path)
    : file_(file), parser_(path), buffer_(std::make_unique_for_overwrite<char[]>(kBufferBytes)) {}

CarmenReader::CarmenReader(CarmenReader&& other) noexcept
    : file_(std::exchange(other.file_, nullptr)),
      parser_(std::move(other.parser_)),
      buffer_(std::move(other.buffer_)),
      begin_(other.begin_),
      end_(other.end_),
      line_number_(other.line_number_),
      eof_(other.eof_),
      cut_(other.cut_),
      failed_(other.failed_),
      error_(other.error_) {}

CarmenReader& CarmenReader::operator=(CarmenReader&& other) noexcept {
  if (this != &other) {
    if (file_ != nullptr) gzclose(file_);
    file_ = std::exchange(other.file_, nullptr);
    parser_ = std::move(other.parser_);
    buffer_ = std::move(other.buffer_);
    begin_ = other.begin_;
    end_ = other.end_;
    line_number_ = other.line_number_;
    eof_ = other.eof_;
    cut_ = other.cut_;
    failed_ = other.failed_;
    error_ = other.error_;
  }
  return *this;
}

CarmenReader::~CarmenReader() {
  if (file_ != nullptr) gzclose(file_);
}

Result<CarmenReader> CarmenReader::open(const std::string& path) {
  errno = 0;
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) {
    const int err = errno;
    if (err == 0) return Error::format(Errc::io, "%s: cannot open (out of memory)", path.c_str());
    const Errc code = err == ENOENT                     ? Errc::not_found
                      : (err == EACCES || err == EPERM) ? Errc::permission
                                                        : Errc::io;
    return Error::from_errno(code, path, err);
  }
  gzbuffer(file, 64 * 1024);  // zlib's input buffer, before the first read allocates it
  CarmenReader reader(file, path);
  // The first read allocates zlib's buffers and shows a file that cannot be read (a directory).
  if (Status s = reader.fill(); !s) return s.error();
  return reader;
}

Status CarmenReader::fill() {
  char* data = buffer_.get();
  if (begin_ > 0) {
    std::memmove(data, data + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  const int got = gzread(file_, data + end_, static_cast<unsigned>(kBufferBytes - end_));
  if (got < 0) {
    int errnum = Z_OK;
    const char* message = gzerror(file_, &errnum);
    if (errnum == Z_ERRNO) message = std::strerror(errno);
    if (line_number_ == 0) return Error::format(Errc::io, "%s: %s", parser_.source().data(), message);
    return Error::format(Errc::io, "%s:%llu: %s", parser_.source().data(),
                         static_cast<unsigned long long>(line_number_ + 1), message);
  }
  if (got == 0) {
    eof_ = true;
    // zlib's "unexpected end of file": the gzip stream stops before its end.
    int errnum = Z_OK;
    gzerror(file_, &errnum);
    cut_ = errnum == Z_BUF_ERROR;
  }
  end_ += static_cast<std::size_t>(got);
  return {};
}

Result<bool> CarmenReader::next(LaserRecord& out) {
  if (failed_) return error_;
  const auto stop = [this](const Error& e) {
    failed_ = true;
    error_ = e;
    return e;
  };
  const char* source = parser_.source().data();  // a std::string's, so NUL-terminated
  for (;;) {
    char* data = buffer_.get();
    const std::size_t unread = end_ - begin_;
    const auto* newline = static_cast<const char*>(std::memchr(data + begin_, '\n', unread));
    std::string_view text;
    if (newline != nullptr) {
      text = std::string_view(data + begin_, static_cast<std::size_t>(newline - (data + begin_)));
      begin_ += text.size() + 1;
    } else if (!eof_) {
      if (unread <= kCarmenMaxLineBytes) {
        if (Status s = fill(); !s) return stop(s.error());
        continue;
      }
      text = std::string_view(data + begin_, unread);  // too long: reported below
    } else if (cut_) {
      return stop(Error::format(Errc::protocol, "%s:%llu: the gzip data ends early: the file is cut", source,
                                static_cast<unsigned long long>(line_number_ + 1)));
    } else if (unread == 0) {
      return false;
    } else {
      text = std::string_view(data + begin_, unread);
      begin_ = end_;
    }
    const bool terminated = newline != nullptr;
    ++line_number_;
    if (text.size() > kCarmenMaxLineBytes) {
      return stop(Error::format(Errc::protocol, "%s:%llu: line longer than %zu bytes", source,
                                static_cast<unsigned long long>(line_number_), kCarmenMaxLineBytes));
    }
    Result<bool> scan = parser_.line(text, line_number_, out);
    if (!scan.ok()) {
      if (terminated) return stop(scan.error());
      return stop(Error::format(Errc::protocol, "%s (the last line, without its newline: the file is cut?)",
                                scan.error().c_str()));
    }
    if (!terminated && !*scan && cut_keyword(text)) {
      return stop(Error::format(Errc::protocol,
                                "%s:%llu: the last line ends inside its keyword: the file is cut", source,
                                static_cast<unsigned long long>(line_number_)));
    }
    if (*scan) return true;
  }
}

}  // namespace sen3bot::slam
