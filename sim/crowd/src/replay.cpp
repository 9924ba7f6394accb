#include "sen3bot/crowd/replay.hpp"

#include <algorithm>
#include <utility>

#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {
namespace {

// Fritsch and Carlson's bound: a cubic Hermite piece whose end tangents are at most 3 times
// its secant velocity does not overshoot its end points along the secant.
constexpr double kMaxTangentPerSecant = 3.0;

// Tangents of a cubic Hermite curve through the samples. At an inner annotation: the
// three-point (non-uniform Catmull-Rom) estimate, the time-weighted mean of the two adjacent
// secant velocities. Being a vector, it turns with the walker whatever the scene's axes are
// (per-axis monotone limiting would stop a walker wherever x or y peaks, as on any curve), and
// being a mean it is no faster than the faster neighbour, which keeps the speed between evenly
// spaced annotations within 1.5 times the adjacent secant speeds. It is then shortened to at most
// kMaxTangentPerSecant times the slower neighbour, so a person who stops stops at the
// annotation instead of overshooting it and walking back. The ends take their one secant.
std::vector<Point2D> tangents(const std::vector<Sample>& samples) {
  const std::size_t n = samples.size();
  std::vector<Point2D> tangent_m_s(n);
  if (n < 2) return tangent_m_s;
  auto secant = [&](std::size_t i) {  // velocity from sample i to i + 1
    return (1.0 / (samples[i + 1].time_s - samples[i].time_s)) * (samples[i + 1].position - samples[i].position);
  };
  tangent_m_s.front() = secant(0);
  tangent_m_s.back() = secant(n - 2);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double before_s = samples[i].time_s - samples[i - 1].time_s;
    const double after_s = samples[i + 1].time_s - samples[i].time_s;
    const Point2D in = secant(i - 1);
    const Point2D out = secant(i);
    const Point2D mean = (1.0 / (before_s + after_s)) * (after_s * in + before_s * out);
    const double limit_m_s = kMaxTangentPerSecant * std::min(msg::norm(in), msg::norm(out));
    const double speed_m_s = msg::norm(mean);
    tangent_m_s[i] = speed_m_s > limit_m_s ? (limit_m_s / speed_m_s) * mean : mean;
  }
  return tangent_m_s;
}

}  // namespace

Replay::Replay(Recording recording) : recording_(std::move(recording)) {
  curves_.reserve(recording_.tracks.size());
  for (const Track& track : recording_.tracks) curves_.push_back({tangents(track.samples), 0});
}

WalkerState Replay::state_at(std::size_t track, double time_s) noexcept {
  if (track >= curves_.size()) return {};
  const std::vector<Sample>& samples = recording_.tracks[track].samples;
  if (!(time_s >= samples.front().time_s && time_s <= samples.back().time_s)) return {};
  if (samples.size() == 1) return {true, samples.front().position, {}};

  // Interval i spans samples i and i + 1, with samples[i].time_s <= time_s (the last one
  // includes its end).
  Curve& curve = curves_[track];
  std::size_t& i = curve.cursor;
  if (time_s < samples[i].time_s) {
    const auto after = std::upper_bound(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(i), time_s,
                                        [](double t, const Sample& s) { return t < s.time_s; });
    i = static_cast<std::size_t>(after - samples.begin()) - 1;
  }
  while (i + 2 < samples.size() && samples[i + 1].time_s <= time_s) ++i;

  const Sample& a = samples[i];
  const Sample& b = samples[i + 1];
  const Point2D m0 = curve.tangent_m_s[i];
  const Point2D m1 = curve.tangent_m_s[i + 1];
  const double h_s = b.time_s - a.time_s;
  const double s = (time_s - a.time_s) / h_s;
  const double s2 = s * s;
  const double s3 = s2 * s;
  // Hermite basis: exactly (1, 0, 0, 0) at s = 0 and (0, 1, 0, 0) at s = 1, so the curve
  // returns the annotations themselves.
  const double h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
  const double h01 = -2.0 * s3 + 3.0 * s2;
  const double h10 = s3 - 2.0 * s2 + s;
  const double h11 = s3 - s2;
  const Point2D position = h00 * a.position + h01 * b.position + h_s * (h10 * m0 + h11 * m1);
  // d/dt of the above; the end points enter as their difference, which stays exact for
  // positions far from the origin.
  const Point2D velocity = (6.0 * (s - s2) / h_s) * (b.position - a.position) + (3.0 * s2 - 4.0 * s + 1.0) * m0 +
                           (3.0 * s2 - 2.0 * s) * m1;
  return {true, position, velocity};
}

void Replay::states_at(double time_s, std::span<WalkerState> out) noexcept {
  const std::size_t n = std::min(out.size(), curves_.size());
  for (std::size_t i = 0; i < n; ++i) out[i] = state_at(i, time_s);
}

}  // namespace sen3bot::crowd
