#include "experiment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sen3bot/crowd/random.hpp"

namespace sen3bot::sim::experiment {

namespace {

using figure::Canvas;
using figure::Px;
using figure::Rgb;

constexpr Rgb kPaper{255, 255, 255};
constexpr Rgb kInk{40, 40, 40};
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kGrey{90, 90, 90};
constexpr Rgb kBoxFills[] = {{170, 200, 240}, {245, 200, 160}, {190, 225, 180}};
constexpr Rgb kBoxEdges[] = {{30, 80, 170}, {190, 90, 0}, {40, 130, 40}};

std::string format(const char* fmt, double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// 1, 2 or 5 times a power of ten, giving about `ticks` steps over span.
double nice_step(double span, int ticks) {
  const double raw = span / ticks;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

}  // namespace

std::vector<Lane> dol_layout(std::uint64_t seed, int boxes) {
  using crowd::unit_uniform;  // the same draws on every platform
  std::mt19937_64 rng(seed);
  const int k = std::clamp(boxes, 1, kMaxBoxes);
  const double slack = (kLaneMaxXM - kLaneMinXM) - (k - 1) * kLaneMinGapM;
  std::vector<Lane> lanes(static_cast<std::size_t>(k));
  std::vector<double> u(lanes.size());
  for (double& v : u) v = unit_uniform(rng) * slack;
  std::sort(u.begin(), u.end());
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    lanes[i].x_m = kLaneMinXM + u[i] + static_cast<double>(i) * kLaneMinGapM;
    lanes[i].phase_m = unit_uniform(rng) * kRoundTripM;
  }
  return lanes;
}

std::vector<world::MoverScript> dol_boxes(const std::vector<Lane>& lanes, double speed_m_s) {
  std::vector<world::MoverScript> movers;
  for (const Lane& lane : lanes) {
    world::MoverScript box;
    box.path = {{lane.x_m, kBoxLowYM}, {lane.x_m, kBoxHighYM}};
    box.speed_m_s = speed_m_s;
    box.size_m = kBoxSizeM;
    box.shape = world::MoverShape::square;
    box.phase_m = lane.phase_m;
    movers.push_back(box);
  }
  return movers;
}

BoxStats box_stats(const std::vector<double>& values) {
  BoxStats b;
  b.q = quartiles(values);
  if (values.empty()) return b;
  const double lo = b.q.q1 - 1.5 * b.q.iqr, hi = b.q.q3 + 1.5 * b.q.iqr;
  b.whisker_low = b.q.q1;
  b.whisker_high = b.q.q3;
  for (const double v : values) {
    if (v < lo || v > hi) {
      b.outliers.push_back(v);
      continue;
    }
    b.whisker_low = std::min(b.whisker_low, v);
    b.whisker_high = std::max(b.whisker_high, v);
  }
  std::sort(b.outliers.begin(), b.outliers.end());
  return b;
}

Canvas draw_travel_time_box_plot(const std::string& title, const std::string& subtitle,
                                 const std::vector<BoxPlotSeries>& series, const BoxPlotText& text) {
  constexpr int kWidth = 760, kHeight = 540;
  constexpr int kLeft = 86, kRight = 24, kTop = 96, kBottom = 78;
  Canvas canvas(kWidth, kHeight, kPaper);
  canvas.text({12, 28}, title, kInk, 0.6, 2);
  canvas.text({12, 52}, subtitle, kGrey, 0.42);
  const int plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;

  std::vector<BoxStats> stats;
  double lo = 1e300, hi = -1e300;
  for (const BoxPlotSeries& s : series) {
    stats.push_back(box_stats(s.values));
    for (const double v : s.values) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (lo > hi) {  // nothing to draw: a sensible empty axis
    lo = 0;
    hi = 60;
  }
  if (hi - lo < 1.0) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double pad = 0.08 * (hi - lo);
  const double step = nice_step(hi - lo + 2 * pad, 6);
  const double y0 = std::floor((lo - pad) / step) * step, y1 = std::ceil((hi + pad) / step) * step;
  auto y_px = [&](double s) { return kTop + plot_h - (s - y0) / (y1 - y0) * plot_h; };

  // Grid, ticks and the axis name.
  for (double s = y0; s <= y1 + 1e-9; s += step) {
    const double y = y_px(s);
    canvas.line({static_cast<double>(kLeft), y}, {static_cast<double>(kLeft + plot_w), y}, kGrid);
    canvas.line({kLeft - 5.0, y}, {static_cast<double>(kLeft), y}, kInk);
    const std::string label = format(step < 1 ? "%.1f" : "%.0f", s);
    canvas.text({kLeft - 9.0 - Canvas::text_width(label, 0.4), y + 5}, label, kInk, 0.4);
  }
  canvas.text({12, kTop - 14.0}, text.axis, kInk, 0.45);
  const std::vector<Px> frame{{kLeft - 1.0, kTop - 1.0},
                              {static_cast<double>(kLeft + plot_w), kTop - 1.0},
                              {static_cast<double>(kLeft + plot_w), static_cast<double>(kTop + plot_h)},
                              {kLeft - 1.0, static_cast<double>(kTop + plot_h)}};
  canvas.outline_polygon(frame, kInk);

  const double slot = series.empty() ? plot_w : static_cast<double>(plot_w) / static_cast<double>(series.size());
  const double half = std::min(70.0, slot / 4);
  for (std::size_t i = 0; i < series.size(); ++i) {
    const BoxStats& b = stats[i];
    const Rgb fill = kBoxFills[i % 3], edge = kBoxEdges[i % 3];
    const double cx = kLeft + (static_cast<double>(i) + 0.5) * slot;
    const std::string label = series[i].label;
    const std::string count = format("%.0f", static_cast<double>(b.q.n)) + " " + text.runs + " runs";
    canvas.text({cx - Canvas::text_width(label, 0.5, 2) / 2.0, kTop + plot_h + 26.0}, label, kInk, 0.5, 2);
    canvas.text({cx - Canvas::text_width(count, 0.4) / 2.0, kTop + plot_h + 48.0}, count, kGrey, 0.4);
    if (b.q.n == 0) {
      const std::string none = "no " + text.runs + " run";
      canvas.text({cx - Canvas::text_width(none, 0.45) / 2.0, kTop + plot_h / 2.0}, none, kGrey, 0.45);
      continue;
    }
    // Whiskers with caps, the box from q1 to q3, the median across it, outliers as rings.
    canvas.line({cx, y_px(b.whisker_low)}, {cx, y_px(b.q.q1)}, edge, 2);
    canvas.line({cx, y_px(b.q.q3)}, {cx, y_px(b.whisker_high)}, edge, 2);
    canvas.line({cx - half / 2, y_px(b.whisker_low)}, {cx + half / 2, y_px(b.whisker_low)}, edge, 2);
    canvas.line({cx - half / 2, y_px(b.whisker_high)}, {cx + half / 2, y_px(b.whisker_high)}, edge, 2);
    const double top = y_px(b.q.q3), bottom = y_px(b.q.q1);
    const std::vector<Px> box{{cx - half, top}, {cx + half, top}, {cx + half, bottom}, {cx - half, bottom}};
    canvas.fill_polygon(box, fill);
    canvas.outline_polygon(box, edge, 2);
    canvas.line({cx - half, y_px(b.q.median)}, {cx + half, y_px(b.q.median)}, kInk, 3);
    canvas.text({cx + half + 6, y_px(b.q.median) + 5}, format("%.1f s", b.q.median), kInk, 0.4, 1, true);
    for (const double v : b.outliers) canvas.ring({cx, y_px(v)}, 4, edge, 2);
  }
  return canvas;
}

}  // namespace sen3bot::sim::experiment
