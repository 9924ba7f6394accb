#include "operations_report.hpp"

#include "sen3bot/nav_figure/case_figure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sen3bot::sim::operations {

namespace {

using figure::Canvas;
using figure::Px;
using figure::Rgb;

using figure::colours::kInk;
using figure::colours::kPaper;
constexpr Rgb kGrey{90, 90, 90};
constexpr Rgb kGuide{160, 160, 160};
constexpr Rgb kGrid{225, 225, 225};
using figure::colours::kWall;
constexpr Rgb kStation{0, 130, 110};
constexpr Rgb kCellFull{30, 80, 170};
// Classifiers in the progressive plot; operations on the map.
constexpr Rgb kSeries[] = {{30, 80, 170}, {200, 90, 0}, {40, 140, 40}, {150, 40, 150}};
constexpr Rgb kPathColours[] = {{220, 40, 40},  {30, 100, 220}, {240, 150, 0}, {40, 160, 60},
                                {150, 60, 190}, {0, 170, 190},  {150, 100, 40}, {230, 80, 170}};

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

Rgb mix(Rgb a, Rgb b, double t) {
  auto c = [t](std::uint8_t x, std::uint8_t y) {
    return static_cast<std::uint8_t>(std::lround(x + (y - x) * std::clamp(t, 0.0, 1.0)));
  };
  return {c(a.r, b.r), c(a.g, b.g), c(a.b, b.b)};
}

void header(Canvas& canvas, const std::string& title, const std::string& subtitle) {
  canvas.text({12, 28}, title, kInk, 0.6, 2);
  canvas.text({12, 52}, subtitle, kGrey, 0.42);
}

void frame(Canvas& canvas, double left, double top, double right, double bottom) {
  const std::vector<Px> box{{left, top}, {right, top}, {right, bottom}, {left, bottom}};
  canvas.outline_polygon(box, kInk);
}

}  // namespace

Canvas draw_confusion(const std::string& title, const std::string& subtitle, const std::vector<Labelled>& results) {
  const std::size_t classes = results.empty() ? 0 : results.front().evaluation.classes.size();
  constexpr int kCell = 64, kNames = 110, kGap = 50, kTop = 130, kBottom = 40;
  const int panel = kNames + static_cast<int>(classes) * kCell;
  const int width = std::max(640, 24 + static_cast<int>(results.size()) * (panel + kGap));
  const int height = kTop + static_cast<int>(classes) * kCell + kBottom;
  Canvas canvas(width, height, kPaper);
  header(canvas, title, subtitle);
  for (std::size_t k = 0; k < results.size(); ++k) {
    const cobot::Evaluation& e = results[k].evaluation;
    const double x0 = 12 + static_cast<double>(k) * (panel + kGap) + kNames;
    const double y0 = kTop;
    canvas.text({x0 - kNames, 80}, results[k].label + format(": accuracy %.3f", e.accuracy), kInk, 0.48, 2);
    canvas.text({x0, y0 - 28}, "recognised as", kGrey, 0.4);
    canvas.text({x0 - kNames, y0 - 8}, "true", kGrey, 0.4);
    for (std::size_t c = 0; c < classes; ++c) {
      const std::string& name = e.classes[c];
      const double cx = x0 + (static_cast<double>(c) + 0.5) * kCell;
      canvas.text({cx - Canvas::text_width(name, 0.38) / 2.0, y0 - 8}, name, kInk, 0.38);
    }
    for (std::size_t r = 0; r < classes; ++r) {
      const double ry = y0 + static_cast<double>(r) * kCell;
      canvas.text({x0 - kNames, ry + kCell / 2.0 + 5}, e.classes[r], kInk, 0.42);
      std::size_t row_total = 0;
      for (const std::size_t n : e.confusion[r]) row_total += n;
      for (std::size_t c = 0; c < classes; ++c) {
        const std::size_t n = e.confusion[r][c];
        const double frac = row_total ? static_cast<double>(n) / static_cast<double>(row_total) : 0.0;
        const double cx = x0 + static_cast<double>(c) * kCell;
        canvas.fill_rect(static_cast<int>(cx), static_cast<int>(ry), kCell, kCell, mix(kPaper, kCellFull, frac));
        const std::string count = format("%.0f", static_cast<double>(n));
        canvas.text({cx + kCell / 2.0 - Canvas::text_width(count, 0.5) / 2.0, ry + kCell / 2.0 + 6}, count,
                    frac > 0.5 ? kPaper : kInk, 0.5, r == c ? 2 : 1);
      }
    }
    frame(canvas, x0 - 0.5, y0 - 0.5, x0 + static_cast<double>(classes) * kCell, y0 + static_cast<double>(classes) * kCell);
  }
  return canvas;
}

Canvas draw_progressive(const std::string& title, const std::string& subtitle, const std::vector<Labelled>& results,
                        double bar) {
  constexpr int kWidth = 820, kHeight = 560;
  constexpr int kLeft = 70, kRight = 24, kTop = 90, kBottom = 70;
  Canvas canvas(kWidth, kHeight, kPaper);
  header(canvas, title, subtitle);
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  auto x_px = [&](double percent) { return kLeft + percent / 100.0 * plot_w; };
  auto y_px = [&](double v) { return kTop + (1.0 - v) * plot_h; };

  for (int i = 0; i <= 10; ++i) {  // x: 0..100 % in tens
    const double x = x_px(10.0 * i);
    canvas.line({x, static_cast<double>(kTop)}, {x, kTop + plot_h}, kGrid);
    canvas.line({x, kTop + plot_h}, {x, kTop + plot_h + 5}, kInk);
    const std::string label = format("%.0f", 10.0 * i);
    canvas.text({x - Canvas::text_width(label, 0.4) / 2.0, kTop + plot_h + 22}, label, kInk, 0.4);
  }
  for (int i = 0; i <= 5; ++i) {  // y: 0..1 in fifths
    const double y = y_px(0.2 * i);
    canvas.line({static_cast<double>(kLeft), y}, {kLeft + plot_w, y}, kGrid);
    canvas.line({kLeft - 5.0, y}, {static_cast<double>(kLeft), y}, kInk);
    const std::string label = format("%.1f", 0.2 * i);
    canvas.text({kLeft - 9.0 - Canvas::text_width(label, 0.4), y + 5}, label, kInk, 0.4);
  }
  const std::string x_name = "path walked (%)";
  canvas.text({kLeft + plot_w / 2 - Canvas::text_width(x_name, 0.45) / 2.0, kHeight - 22.0}, x_name, kInk, 0.45);
  canvas.text({12, kTop - 12.0}, "probability of the right operation / fraction of paths", kInk, 0.45);
  // Guides: the confidence bar and the 60 % mark.
  const std::vector<Px> bar_line{{static_cast<double>(kLeft), y_px(bar)}, {kLeft + plot_w, y_px(bar)}};
  canvas.dashed_polyline(bar_line, kGuide, 1, 6, 5);
  const std::vector<Px> mark{{x_px(60), static_cast<double>(kTop)}, {x_px(60), kTop + plot_h}};
  canvas.dashed_polyline(mark, kGuide, 1, 6, 5);
  canvas.text({x_px(60) + 4, kTop + plot_h - 8}, "60 %", kGrey, 0.4);
  frame(canvas, kLeft - 0.5, kTop - 0.5, kLeft + plot_w, kTop + plot_h);

  struct Entry {
    std::string text;
    Rgb colour;
    bool dashed;
  };
  std::vector<Entry> legend;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const cobot::Evaluation& e = results[k].evaluation;
    const Rgb colour = kSeries[k % std::size(kSeries)];
    std::vector<Px> mean, confident;
    for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) {
      const double percent = 100.0 * cobot::kPrefixFractions[s];
      mean.push_back({x_px(percent), y_px(e.right_probability[s])});
      confident.push_back({x_px(percent), y_px(e.confident[s])});
    }
    canvas.polyline(mean, colour, 3);
    canvas.dashed_polyline(confident, colour, 2, 9, 6);
    for (const Px& p : mean) canvas.disc(p, 4, colour);
    for (const Px& p : confident) canvas.ring(p, 4, colour, 2);
    legend.push_back({results[k].label + ": mean probability of the right operation", colour, false});
    legend.push_back({results[k].label + format(": fraction of paths above %.2f", bar), colour, true});
  }
  // The legend in the lower right, over a white box.
  int legend_w = 0;
  for (const Entry& e : legend) legend_w = std::max(legend_w, Canvas::text_width(e.text, 0.4));
  legend_w += 60;
  const double lx = kLeft + plot_w - legend_w - 10, ly = kTop + plot_h - 22.0 * static_cast<double>(legend.size()) - 40;
  canvas.fill_rect(static_cast<int>(lx), static_cast<int>(ly), legend_w, 22 * static_cast<int>(legend.size()) + 10, kPaper);
  frame(canvas, lx, ly, lx + legend_w, ly + 22.0 * static_cast<double>(legend.size()) + 10);
  for (std::size_t i = 0; i < legend.size(); ++i) {
    const double y = ly + 18 + 22.0 * static_cast<double>(i);
    const std::vector<Px> sample{{lx + 8, y - 4}, {lx + 44, y - 4}};
    if (legend[i].dashed)
      canvas.dashed_polyline(sample, legend[i].colour, 2, 9, 6);
    else
      canvas.polyline(sample, legend[i].colour, 3);
    canvas.text({lx + 52, y}, legend[i].text, kInk, 0.4);
  }
  return canvas;
}

Canvas draw_example_paths(const std::string& title, const std::string& subtitle, const nav::OccupancyMap& map,
                          const cobot::OperationsConfig& config, const std::vector<ExamplePath>& paths) {
  constexpr double kPxPerM = 60;
  constexpr int kLeft = 60, kTop = 80, kBottom = 50, kLegend = 300;
  const double map_w = map.width() * map.resolution_m(), map_h = map.height() * map.resolution_m();
  const int width = kLeft + static_cast<int>(map_w * kPxPerM) + 20 + kLegend;
  const int height = kTop + static_cast<int>(map_h * kPxPerM) + kBottom;
  Canvas canvas(width, height, kPaper);
  header(canvas, title, subtitle);
  const figure::View view{map.origin_x_m(), map.origin_y_m(), kPxPerM, static_cast<double>(kLeft),
                          static_cast<double>(kTop) + map_h * kPxPerM};
  // The map's occupied cells (axis-aligned maps: the lab's yaw is 0).
  for (int r = 0; r < map.height(); ++r)
    for (int c = 0; c < map.width(); ++c)
      if (map.at(c, r) >= 50) {
        // Pixel edges from the cell's edges, so neighbouring cells leave no seams.
        const Px a = view(map.origin_x_m() + c * map.resolution_m(), map.origin_y_m() + (r + 1) * map.resolution_m());
        const Px b = view(map.origin_x_m() + (c + 1) * map.resolution_m(), map.origin_y_m() + r * map.resolution_m());
        const int x0 = static_cast<int>(std::lround(a.x)), y0 = static_cast<int>(std::lround(a.y));
        canvas.fill_rect(x0, y0, static_cast<int>(std::lround(b.x)) - x0, static_cast<int>(std::lround(b.y)) - y0, kWall);
      }
  // Axes in metres.
  const Px lower_left = view(map.origin_x_m(), map.origin_y_m());
  for (int m = 0; m <= static_cast<int>(map_w); ++m) {
    const Px p = view(map.origin_x_m() + m, map.origin_y_m());
    canvas.line({p.x, lower_left.y}, {p.x, lower_left.y + 5}, kInk);
    const std::string label = format("%.0f", static_cast<double>(m));
    canvas.text({p.x - Canvas::text_width(label, 0.4) / 2.0, lower_left.y + 20}, label, kInk, 0.4);
  }
  for (int m = 0; m <= static_cast<int>(map_h); ++m) {
    const Px p = view(map.origin_x_m(), map.origin_y_m() + m);
    canvas.line({lower_left.x - 5, p.y}, {lower_left.x, p.y}, kInk);
    const std::string label = format("%.0f", static_cast<double>(m));
    canvas.text({lower_left.x - 9 - Canvas::text_width(label, 0.4), p.y + 5}, label, kInk, 0.4);
  }
  canvas.text({lower_left.x + map_w * kPxPerM / 2 - 20, lower_left.y + 40}, "x (m)", kInk, 0.45);
  canvas.text({8, static_cast<double>(kTop) - 8}, "y (m)", kInk, 0.45);

  for (std::size_t k = 0; k < paths.size(); ++k) {
    const Rgb colour = kPathColours[k % std::size(kPathColours)];
    std::vector<Px> line;
    for (std::size_t i = 0; i + 1 < paths[k].xy.size(); i += 2) line.push_back(view(paths[k].xy[i], paths[k].xy[i + 1]));
    if (line.empty()) continue;
    canvas.polyline(line, colour, 2);
    canvas.ring(line.front(), 6, colour, 2);
    canvas.disc(line.back(), 5, colour);
  }
  for (const cobot::Workstation& s : config.stations) {
    const Px p = view(s.position.x_m, s.position.y_m);
    canvas.ring(p, s.radius_m * kPxPerM, kStation, 2);
    canvas.disc(p, 3, kStation);
    canvas.text({p.x + 8, p.y - 8}, s.name, kStation, 0.42, 1, true);
  }
  // Legend: each path's operation and its stations; start ring, end disc.
  const double lx = kLeft + map_w * kPxPerM + 20;
  double ly = kTop + 10.0;
  for (std::size_t k = 0; k < paths.size(); ++k) {
    const Rgb colour = kPathColours[k % std::size(kPathColours)];
    canvas.line({lx, ly - 4}, {lx + 30, ly - 4}, colour, 3);
    // "name\nwhat it visits": the name, and under it in grey what it visits.
    const std::size_t cut = paths[k].label.find('\n');
    canvas.text({lx + 38, ly}, paths[k].label.substr(0, cut), kInk, 0.45, 1);
    if (cut != std::string::npos) {
      ly += 18;
      canvas.text({lx + 38, ly}, paths[k].label.substr(cut + 1), kGrey, 0.36);
    }
    ly += 26;
  }
  ly += 10;
  canvas.ring({lx + 6, ly - 4}, 6, kInk, 2);
  canvas.text({lx + 20, ly}, "first point recorded", kInk, 0.4);
  ly += 20;
  canvas.disc({lx + 6, ly - 4}, 5, kInk);
  canvas.text({lx + 20, ly}, "last point", kInk, 0.4);
  ly += 20;
  canvas.ring({lx + 6, ly - 4}, 8, kStation, 2);
  canvas.text({lx + 20, ly}, "workstation and its radius", kInk, 0.4);
  return canvas;
}

}  // namespace sen3bot::sim::operations
