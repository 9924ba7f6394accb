#pragma once
// What a laser at shin height sees of a walking person: two legs, circles of kLegRadiusM. The
// legs swing fore and aft along the heading in antiphase, sinusoidally (the first harmonic of
// the stance foot staying put while the other passes it), half a step length each way, so at
// double support they are one step length apart; sideways each keeps kLegSpreadM off the
// walking line. Standing, the feet are side by side, 2 kLegSpreadM apart.
//
// Gait against speed v: step frequency f = 1.6 Hz (v / 1 m/s)^0.58. The exponent is Grieve &
// Gear's log-log fit for adults ("The relationships between length of stride, step frequency,
// time of swing and speed of walking for children and adults", Ergonomics 9(5), 1966,
// doi:10.1080/00140136608964399; quoted as SF = a V^0.58 by Terrier & Schutz, Eur J Appl
// Physiol 90, 2003). The scale puts an adult at the preferred 1.3 m/s at 1.86 steps/s (112
// steps/min), the usual adult cadence of 110 to 115 steps/min (Perry & Burnfield, Gait
// Analysis, 2010). The step length v / f = v^0.42 / 1.6 m (0.47 m at 0.5 m/s, 0.70 m at
// 1.3 m/s) stops growing at kGaitMaxSpeedM_S, about where people start to run; faster, only
// the frequency grows.
//
// The phase advances by pi per step length walked (a stride of two steps is one cycle), so it
// is a pure function of the distance walked: deterministic, and frozen while standing.
#include <array>

#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {

using msg::Point2D;

inline constexpr double kLegRadiusM = 0.06;
inline constexpr double kLegSpreadM = 0.1;           // each leg's centre off the walking line
inline constexpr double kGaitMaxSpeedM_S = 2.0;      // the step length's speed cap
inline constexpr double kHeadingMinSpeedM_S = 0.05;  // slower, the heading is kept: noise, not walking

struct Gait {
  double phase_rad = 0.0;    // [0, 2 pi); 0 and pi: feet side by side
  double heading_rad = 0.0;  // the last walking direction
};

// The gait relation above; 0 at rest.
[[nodiscard]] double step_frequency_hz(double speed_m_s) noexcept;
[[nodiscard]] double step_length_m(double speed_m_s) noexcept;

// One time step of a person moving at `velocity`.
void advance(Gait& gait, Point2D velocity, double dt_s) noexcept;

// The leg centres of a person at `centre` walking at speed_m_s: the left leg first.
[[nodiscard]] std::array<Point2D, 2> leg_centres(Point2D centre, const Gait& gait, double speed_m_s) noexcept;

}  // namespace sen3bot::crowd
