#pragma once
// The pieces of `sen3bot-sim experiment dol` (cmd_experiment.cpp) that stand on their own: the
// thesis' moving-obstacle layout drawn from a seed, the quartiles of a sample, and the travel
// time box plot. docs/navigation.md describes the experiment.
#include <cstdint>
#include <string>
#include <vector>

#include "sen3bot/crowd/metrics.hpp"
#include "sen3bot/figure/canvas.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::sim::experiment {

// The arena (config/maps/arena.yaml): free interior x in [0, 10] m, y in [0, 6] m. The boxes
// walk vertical lanes across the short side, the robot crosses the long one.
inline constexpr double kLaneMinXM = 2.0;
inline constexpr double kLaneMaxXM = 8.0;
inline constexpr double kLaneMinGapM = 0.8;
inline constexpr double kBoxLowYM = 0.25;   // the lane's ends: the box's centre turns here
inline constexpr double kBoxHighYM = 5.75;
inline constexpr double kBoxSizeM = 0.2;    // the thesis' 20 x 20 cm boxes
inline constexpr double kRoundTripM = 2.0 * (kBoxHighYM - kBoxLowYM);  // 11 m
inline constexpr int kMaxBoxes = 8;

struct Lane {
  double x_m = 0;      // the lane: x = const
  double phase_m = 0;  // where along its 11 m round trip the box starts, [0, kRoundTripM)
};

// `boxes` lanes (1..kMaxBoxes), sorted by x, inside [kLaneMinXM, kLaneMaxXM] and at least
// kLaneMinGapM apart, each with its phase; a pure function of the seed. The lanes are uniform
// over every such arrangement: sorted draws in the slack (6 m less the gaps), each gap added back.
[[nodiscard]] std::vector<Lane> dol_layout(std::uint64_t seed, int boxes);

// The lanes as the world's movers: square 0.2 m boxes walking (x, 0.25) <-> (x, 5.75) m at speed.
[[nodiscard]] std::vector<world::MoverScript> dol_boxes(const std::vector<Lane>& lanes, double speed_m_s);

// Quartiles by linear interpolation between order statistics (numpy's default): the crowd
// metrics' own.
using crowd::Quartiles;
[[nodiscard]] inline Quartiles quartiles(std::vector<double> values) { return crowd::quartiles(values); }

// One box of a box plot: quartiles, whiskers to the furthest sample within 1.5 IQR of the box,
// the samples beyond them as outliers.
struct BoxStats {
  Quartiles q;
  double whisker_low = 0, whisker_high = 0;
  std::vector<double> outliers;
};
[[nodiscard]] BoxStats box_stats(const std::vector<double>& values);

struct BoxPlotSeries {
  std::string label;            // under the box, e.g. "DOL"
  std::vector<double> values;   // seconds
};

// The words of the box plot (the defaults are experiment dol's).
struct BoxPlotText {
  std::string axis = "travel time (s)";  // the y axis' name
  std::string runs = "smooth";           // under each box: "N smooth runs", or "no smooth run"
};

// The thesis' Figure 1.32 for our runs: a box per series, y in seconds.
[[nodiscard]] figure::Canvas draw_travel_time_box_plot(const std::string& title, const std::string& subtitle,
                                                       const std::vector<BoxPlotSeries>& series,
                                                       const BoxPlotText& text = {});

}  // namespace sen3bot::sim::experiment
