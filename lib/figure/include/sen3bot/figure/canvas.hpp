#pragma once
// A raster for figures: RGB pixels drawn on with anti-aliased lines, polygons, discs
// and text (OpenCV's Hershey simplex font) at sub-pixel coordinates. Nothing leaves it but
// its pixels and write_png().
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sen3bot::figure {

struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

// Canvas coordinates: x right, y down, in pixels; integer values are pixel centres.
struct Px {
  double x = 0;
  double y = 0;
};

class Canvas {
 public:
  Canvas(int width, int height, Rgb background);

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  // Pixel (x, y); both must be inside the canvas.
  [[nodiscard]] Rgb at(int x, int y) const noexcept;

  // Pixels x .. x+w-1, y .. y+h-1 (clipped).
  void fill_rect(int x, int y, int w, int h, Rgb colour);
  void line(Px a, Px b, Rgb colour, int thickness = 1);
  void polyline(std::span<const Px> points, Rgb colour, int thickness = 1);
  // Dashes of dash_px with gaps of gap_px, measured along the whole polyline.
  void dashed_polyline(std::span<const Px> points, Rgb colour, int thickness, double dash_px, double gap_px);
  void fill_polygon(std::span<const Px> points, Rgb colour);
  void outline_polygon(std::span<const Px> points, Rgb colour, int thickness = 1);
  void disc(Px centre, double radius_px, Rgb colour);
  void ring(Px centre, double radius_px, Rgb colour, int thickness = 1);

  // Text whose baseline starts at `at`; a size of 0.5 gives capitals about 11 px tall. With a
  // halo the glyphs are first drawn wider in the background colour, to stay readable over lines.
  void text(Px at, std::string_view s, Rgb colour, double size, int thickness = 1, bool halo = false);
  [[nodiscard]] static int text_width(std::string_view s, double size, int thickness = 1);
  [[nodiscard]] static int text_height(double size, int thickness = 1);  // capitals, above the baseline

  // PNG through OpenCV's encoder; false when the file cannot be written.
  [[nodiscard]] bool write_png(const std::string& path) const;

 private:
  int width_;
  int height_;
  Rgb background_;
  std::vector<std::uint8_t> bgr_;  // OpenCV's channel order, row-major
};

// Map metres (x right, y up) to canvas pixels: the plot's lower-left corner and its scale.
struct View {
  double x0_m = 0;  // the map point drawn at (left_px, bottom_px)
  double y0_m = 0;
  double px_per_m = 40;
  double left_px = 0;
  double bottom_px = 0;

  [[nodiscard]] Px operator()(double x_m, double y_m) const noexcept {
    return {left_px + (x_m - x0_m) * px_per_m, bottom_px - (y_m - y0_m) * px_per_m};
  }
};

}  // namespace sen3bot::figure
