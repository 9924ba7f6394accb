#include "sen3bot/vda5050/types.hpp"

#include <cstdio>
#include <ctime>
#include <limits>

namespace sen3bot::vda5050 {

namespace {

bool digits(std::string_view text, std::size_t at, std::size_t count, int& value) noexcept {
  if (at + count > text.size()) return false;
  value = 0;
  for (std::size_t i = at; i < at + count; ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
    value = value * 10 + (text[i] - '0');
  }
  return true;
}

// Days from 1970-01-01 to a proleptic Gregorian date (Howard Hinnant's days_from_civil).
std::int64_t days_from_civil(int y, int m, int d) noexcept {
  y -= m <= 2 ? 1 : 0;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + doe - 719468;
}

}  // namespace

std::string_view to_string(Version version) noexcept {
  return version == Version::v2_0_0 ? "2.0.0" : "2.1.0";
}

std::optional<Version> parse_version(std::string_view text) noexcept {
  if (text == "2.0.0") return Version::v2_0_0;
  if (text == "2.1.0") return Version::v2_1_0;
  return std::nullopt;
}

Id iso8601(std::int64_t unix_ns) noexcept {
  const std::time_t seconds = static_cast<std::time_t>(unix_ns / 1'000'000'000);
  const int hundredths = static_cast<int>((unix_ns % 1'000'000'000) / 10'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[40];
  const int n = std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%02dZ", utc.tm_year + 1900, utc.tm_mon + 1,
                              utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, hundredths < 0 ? 0 : hundredths);
  Id id;
  (void)id.assign(std::string_view(text, n > 0 ? static_cast<std::size_t>(n) : 0));
  return id;
}

bool parse_iso8601(std::string_view text, std::int64_t& unix_ns) noexcept {
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  if (!digits(text, 0, 4, year) || text.size() < 20 || text[4] != '-' || !digits(text, 5, 2, month) || text[7] != '-' ||
      !digits(text, 8, 2, day) || (text[10] != 'T' && text[10] != 't') || !digits(text, 11, 2, hour) || text[13] != ':' ||
      !digits(text, 14, 2, minute) || text[16] != ':' || !digits(text, 17, 2, second))
    return false;
  if (month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 || second > 60) return false;
  std::size_t at = 19;
  std::int64_t fraction_ns = 0;
  if (at < text.size() && text[at] == '.') {
    ++at;
    std::int64_t scale = 100'000'000;
    const std::size_t first = at;
    for (; at < text.size() && text[at] >= '0' && text[at] <= '9'; ++at) {
      fraction_ns += (text[at] - '0') * scale;
      scale /= 10;
    }
    if (at == first) return false;
  }
  std::int64_t offset_s = 0;
  if (at < text.size() && (text[at] == 'Z' || text[at] == 'z')) {
    ++at;
  } else if (at < text.size() && (text[at] == '+' || text[at] == '-')) {
    int oh = 0, om = 0;
    if (!digits(text, at + 1, 2, oh) || at + 3 >= text.size() || text[at + 3] != ':' || !digits(text, at + 4, 2, om)) return false;
    offset_s = (text[at] == '+' ? 1 : -1) * static_cast<std::int64_t>(oh * 3600 + om * 60);
    at += 6;
  } else {
    return false;
  }
  if (at != text.size()) return false;
  const std::int64_t seconds = days_from_civil(year, month, day) * 86400 + hour * 3600 + minute * 60 + second - offset_s;
  // Unix nanoseconds in 64 bits span 1677 to 2262: a date outside is no time here.
  constexpr std::int64_t kLimit = std::numeric_limits<std::int64_t>::max() / 1'000'000'000 - 1;
  if (seconds > kLimit || seconds < -kLimit) return false;
  unix_ns = seconds * 1'000'000'000 + fraction_ns;
  return true;
}

std::string_view to_string(BlockingType value) noexcept {
  switch (value) {
    case BlockingType::none: return "NONE";
    case BlockingType::soft: return "SOFT";
    case BlockingType::hard: return "HARD";
  }
  return "NONE";
}

std::string_view to_string(ActionStatus value) noexcept {
  switch (value) {
    case ActionStatus::waiting: return "WAITING";
    case ActionStatus::initializing: return "INITIALIZING";
    case ActionStatus::running: return "RUNNING";
    case ActionStatus::paused: return "PAUSED";
    case ActionStatus::finished: return "FINISHED";
    case ActionStatus::failed: return "FAILED";
  }
  return "FAILED";
}

std::string_view to_string(ErrorLevel value) noexcept {
  return value == ErrorLevel::fatal ? "FATAL" : "WARNING";
}

std::string_view to_string(ConnectionState value) noexcept {
  switch (value) {
    case ConnectionState::online: return "ONLINE";
    case ConnectionState::offline: return "OFFLINE";
    case ConnectionState::connection_broken: return "CONNECTIONBROKEN";
  }
  return "CONNECTIONBROKEN";
}

std::string_view to_string(EStop value) noexcept {
  switch (value) {
    case EStop::autoack: return "AUTOACK";
    case EStop::manual: return "MANUAL";
    case EStop::remote: return "REMOTE";
    case EStop::none: return "NONE";
  }
  return "NONE";
}

std::string_view to_string(OperatingMode value) noexcept {
  switch (value) {
    case OperatingMode::automatic: return "AUTOMATIC";
    case OperatingMode::semiautomatic: return "SEMIAUTOMATIC";
    case OperatingMode::manual: return "MANUAL";
    case OperatingMode::service: return "SERVICE";
    case OperatingMode::teachin: return "TEACHIN";
  }
  return "AUTOMATIC";
}

}  // namespace sen3bot::vda5050
