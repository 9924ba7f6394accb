#pragma once
// The schemas' enumeration names and ranges, and the header's version rule: shared by the
// decoders and the encoders.
#include <string_view>

#include "sen3bot/vda5050/codec.hpp"

namespace sen3bot::vda5050::wire {

// Ranges the schemas set.
inline constexpr double kThetaLimit = 3.14159265359;             // node/edge theta, orientation
inline constexpr double kDeviationThetaLimit = 3.141592654;      // allowedDeviationTheta

inline constexpr std::string_view kBlockingNames[] = {"NONE", "SOFT", "HARD"};
inline constexpr std::string_view kActionStatusNames[] = {"WAITING", "INITIALIZING", "RUNNING", "PAUSED", "FINISHED", "FAILED"};
inline constexpr std::string_view kErrorLevelNames[] = {"WARNING", "FATAL"};
inline constexpr std::string_view kConnectionNames[] = {"ONLINE", "OFFLINE", "CONNECTIONBROKEN"};
inline constexpr std::string_view kEStopNames[] = {"AUTOACK", "MANUAL", "REMOTE", "NONE"};
inline constexpr std::string_view kOperatingModeNames[] = {"AUTOMATIC", "SEMIAUTOMATIC", "MANUAL", "SERVICE", "TEACHIN"};
inline constexpr std::string_view kMapStatusNames[] = {"ENABLED", "DISABLED"};
inline constexpr std::string_view kCorridorRefNames[] = {"KINEMATICCENTER", "CONTOUR"};
inline constexpr std::string_view kInfoLevelNames[] = {"INFO", "DEBUG"};

// "2.<minor>.<patch>" with the site's minor.
inline bool version_matches(std::string_view text, Version version) noexcept {
  std::size_t i = 0;
  unsigned parts[3] = {0, 0, 0};
  for (int p = 0; p < 3; ++p) {
    const std::size_t start = i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9' && i - start < 6) parts[p] = parts[p] * 10 + static_cast<unsigned>(text[i++] - '0');
    if (i == start) return false;
    if (p < 2) {
      if (i == text.size() || text[i] != '.') return false;
      ++i;
    }
  }
  if (i != text.size()) return false;
  return parts[0] == 2 && parts[1] == (version == Version::v2_0_0 ? 0u : 1u);
}

}  // namespace sen3bot::vda5050::wire
