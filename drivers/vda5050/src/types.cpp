#include "sen3bot/vda5050/types.hpp"

#include <cstdio>
#include <ctime>

namespace sen3bot::vda5050 {

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
