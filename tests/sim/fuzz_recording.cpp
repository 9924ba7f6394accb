// Fuzz target: any bytes are a recording or a refusal with a reason, never a crash or a hang. A
// recording's walks are non-empty with increasing times, and its replay gives back each
// annotation and never walks faster than twice the jump limit (a cubic Hermite piece peaks at
// twice its largest tangent or secant, and none of those exceeds the limit).
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <utility>

#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/replay.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace {

constexpr std::size_t kTracksChecked = 16;
constexpr std::size_t kSamplesChecked = 16;
constexpr double kRoundingSlack = 1e-5;  // times are frames times seconds_per_frame, rounded

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::crowd;
  using sen3bot::msg::norm;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  sen3bot::Result<Recording> parsed = parse_recording(text, "fuzz");
  if (!parsed) {
    if (parsed.error().message().empty()) __builtin_trap();
    return 0;
  }
  for (const Track& track : parsed->tracks) {
    if (track.samples.empty()) __builtin_trap();
    for (std::size_t i = 1; i < track.samples.size(); ++i) {
      if (!(track.samples[i].time_s > track.samples[i - 1].time_s)) __builtin_trap();
    }
  }
  const Summary summary = summarize(*parsed);
  if (summary.samples == 0 || summary.most_at_once == 0 || summary.people > summary.tracks) __builtin_trap();
  (void)busiest_point(*parsed);

  Replay replay(std::move(parsed).value());
  const double max_speed_m_s = 2.0 * RecordingOptions{}.max_speed_m_s * (1.0 + kRoundingSlack);
  for (std::size_t t = 0; t < replay.track_count() && t < kTracksChecked; ++t) {
    const auto& samples = replay.recording().tracks[t].samples;
    for (std::size_t i = 0; i < samples.size() && i < kSamplesChecked; ++i) {
      const WalkerState at = replay.state_at(t, samples[i].time_s);
      if (!at.visible || !(norm(at.position - samples[i].position) <= 1e-9 * (1.0 + norm(samples[i].position)))) {
        __builtin_trap();
      }
      if (i + 1 == samples.size()) continue;
      const WalkerState between = replay.state_at(t, 0.5 * (samples[i].time_s + samples[i + 1].time_s));
      if (!between.visible || !(norm(between.velocity_m_s) <= max_speed_m_s)) __builtin_trap();
    }
  }
  std::array<WalkerState, 8> states;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const double time_s : {summary.end_s, summary.start_s, 0.5 * (summary.start_s + summary.end_s), -1.0, nan}) {
    replay.states_at(time_s, states);
  }
  return 0;
}
