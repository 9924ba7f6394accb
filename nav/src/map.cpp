#include "sen3bot/nav/map.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "sen3bot/yaml/reader.hpp"

namespace sen3bot::nav {

OccupancyMap::OccupancyMap(int width, int height, double resolution_m, double origin_x_m,
                           double origin_y_m, double origin_yaw_rad)
    : geometry_(width, height, resolution_m, origin_x_m, origin_y_m, origin_yaw_rad),
      cells_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0) {}

namespace {

constexpr double kAnyNumber = std::numeric_limits<double>::max();

MapYaml read_map_yaml(const yaml::Reader& r) {
  r.allow_only({"image", "resolution", "origin", "occupied_thresh", "free_thresh", "negate", "mode"});
  MapYaml y;
  y.image = r.text("image");
  if (y.image.empty()) r.fail("image", "is empty");
  y.resolution_m = r.number("resolution", -kAnyNumber, kAnyNumber);
  if (y.resolution_m <= 0.0) r.fail("resolution", "expected a number > 0 (metres per cell)");
  const std::vector<double> origin = r.child("origin").numbers_here("[x, y, yaw]", 3, 3);
  y.origin_x_m = origin[0];
  y.origin_y_m = origin[1];
  y.origin_yaw_rad = origin[2];
  if (r.has("occupied_thresh")) y.occupied_thresh = r.number("occupied_thresh", 0.0, 1.0);
  if (r.has("free_thresh")) y.free_thresh = r.number("free_thresh", 0.0, 1.0);
  // map_server writes 0 or 1.
  if (r.has("negate")) y.negate = r.choice("negate", {"0", "false", "1", "true"}) >= 2;
  constexpr MapMode kModes[] = {MapMode::trinary, MapMode::scale, MapMode::raw};
  if (r.has("mode")) y.mode = kModes[r.choice("mode", {"trinary", "scale", "raw"})];
  if (y.free_thresh >= y.occupied_thresh) {
    char problem[96];
    std::snprintf(problem, sizeof problem, "%g must be below occupied_thresh %g", y.free_thresh, y.occupied_thresh);
    r.fail("free_thresh", problem);
  }
  return y;
}

}  // namespace

Result<MapYaml> parse_map_yaml(std::string_view text, std::string_view source) {
  return yaml::parse<MapYaml>(text, std::string(source), read_map_yaml);
}

namespace {

// PGM header tokens: whitespace-separated, '#' comments to end of line.
struct PgmCursor {
  std::string_view bytes;
  std::size_t pos = 0;

  void skip_space_and_comments() {
    while (pos < bytes.size()) {
      const char c = bytes[pos];
      if (c == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n' && bytes[pos] != '\r') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(c)) != 0) {
        ++pos;
      } else {
        return;
      }
    }
  }

  bool read_uint(long& out, long limit) {
    skip_space_and_comments();
    const std::size_t start = pos;
    out = 0;
    while (pos < bytes.size() && std::isdigit(static_cast<unsigned char>(bytes[pos])) != 0) {
      out = out * 10 + (bytes[pos] - '0');
      if (out > limit) return false;
      ++pos;
    }
    return pos > start;
  }
};

Error pgm_error(std::string_view source, const char* what) {
  return Error::format(Errc::protocol, "%.*s: PGM: %s", static_cast<int>(source.size()), source.data(), what);
}

}  // namespace

Result<PgmImage> parse_pgm(std::string_view bytes, std::string_view source) {
  if (bytes.size() < 2 || bytes[0] != 'P' || (bytes[1] != '5' && bytes[1] != '2')) {
    return pgm_error(source, "not a PGM (magic must be P5 or P2)");
  }
  const bool binary = bytes[1] == '5';
  PgmCursor cur{bytes, 2};
  long width = 0;
  long height = 0;
  long max_value = 0;
  constexpr long kDimensionLimit = 1L << 16;
  if (!cur.read_uint(width, kDimensionLimit) || width == 0) return pgm_error(source, "bad or missing width");
  if (!cur.read_uint(height, kDimensionLimit) || height == 0) return pgm_error(source, "bad or missing height");
  if (!cur.read_uint(max_value, 65535) || max_value == 0) {
    return pgm_error(source, "bad or missing maximum value (1..65535)");
  }
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (count > kMaxMapCells) return pgm_error(source, "image too large");
  PgmImage image;
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  image.max_value = static_cast<int>(max_value);
  if (binary) {
    // Exactly one whitespace byte separates the header from the raster.
    if (cur.pos >= bytes.size() || std::isspace(static_cast<unsigned char>(bytes[cur.pos])) == 0) {
      return pgm_error(source, "missing whitespace after the header");
    }
    ++cur.pos;
    const std::size_t bytes_per_pixel = max_value > 255 ? 2 : 1;
    if (bytes.size() - cur.pos < count * bytes_per_pixel) return pgm_error(source, "raster is truncated");
    image.pixels.resize(count);
    const auto* raster = reinterpret_cast<const unsigned char*>(bytes.data() + cur.pos);
    for (std::size_t i = 0; i < count; ++i) {
      const unsigned v = bytes_per_pixel == 2 ? (raster[2 * i] << 8u) | raster[2 * i + 1] : raster[i];
      if (static_cast<long>(v) > max_value) return pgm_error(source, "pixel above the maximum value");
      image.pixels[i] = static_cast<std::uint16_t>(v);
    }
  } else {
    image.pixels.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      long v = 0;
      if (!cur.read_uint(v, max_value)) return pgm_error(source, "ASCII raster is truncated or has a bad value");
      image.pixels[i] = static_cast<std::uint16_t>(v);
    }
  }
  return image;
}

OccupancyMap occupancy_from_image(const PgmImage& image, const MapYaml& yaml) {
  OccupancyMap map(image.width, image.height, yaml.resolution_m, yaml.origin_x_m, yaml.origin_y_m,
                   yaml.origin_yaw_rad);
  const double max_value = image.max_value;
  for (int image_row = 0; image_row < image.height; ++image_row) {
    const int row = image.height - 1 - image_row;  // the image's top row is the map's last
    for (int col = 0; col < image.width; ++col) {
      const unsigned v = image.pixels[static_cast<std::size_t>(image_row) * static_cast<std::size_t>(image.width) +
                                      static_cast<std::size_t>(col)];
      std::int8_t out = kUnknownOccupancy;
      if (yaml.mode == MapMode::raw) {
        out = v <= 100 ? static_cast<std::int8_t>(v) : kUnknownOccupancy;
      } else {
        const double p = yaml.negate ? v / max_value : (max_value - v) / max_value;
        if (p >= yaml.occupied_thresh) {
          out = kOccupiedOccupancy;
        } else if (p <= yaml.free_thresh) {
          out = 0;
        } else if (yaml.mode == MapMode::scale) {
          const double ratio = (p - yaml.free_thresh) / (yaml.occupied_thresh - yaml.free_thresh);
          out = static_cast<std::int8_t>(std::clamp(std::rint(ratio * 100.0), 1.0, 99.0));
        }
      }
      map.set(col, row, out);
    }
  }
  return map;
}

namespace {

Result<std::string> read_whole_file(const std::string& path, std::size_t limit) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open", path.c_str());
  std::string text;
  char buffer[4096];
  while (in) {
    in.read(buffer, sizeof buffer);
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > limit) return Error::format(Errc::capacity, "%s: larger than %zu bytes", path.c_str(), limit);
  }
  return text;
}

}  // namespace

Result<OccupancyMap> load_map(const std::string& yaml_path) {
  auto text = read_whole_file(yaml_path, 64 * 1024);
  if (!text) return text.error();
  auto map_yaml = parse_map_yaml(*text, yaml_path);
  if (!map_yaml) return map_yaml.error();
  const std::string image_name = yaml::relative_to(yaml_path, map_yaml->image);
  auto bytes = read_whole_file(image_name, 2 * kMaxMapCells + 4096);
  if (!bytes) return Error::format(bytes.error().code(), "%s: image: %s", yaml_path.c_str(), bytes.error().c_str());
  auto image = parse_pgm(*bytes, image_name);
  if (!image) return image.error();
  return occupancy_from_image(*image, *map_yaml);
}

namespace {

std::string commented(std::string_view comment) {
  std::string out;
  std::size_t start = 0;
  while (start < comment.size()) {
    const std::size_t end = std::min(comment.find('\n', start), comment.size());
    out += "# ";
    out.append(comment.substr(start, end - start));
    out += '\n';
    start = end + 1;
  }
  return out;
}

Status write_whole_file(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Error::format(Errc::io, "%s: cannot create", path.c_str());
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) return Error::format(Errc::io, "%s: write failed", path.c_str());
  return {};
}

}  // namespace

Status save_map(const OccupancyMap& map, const std::string& yaml_path, std::string_view comment) {
  if (map.width() <= 0 || map.height() <= 0) return Error::format(Errc::invalid_argument, "%s: a map with no cells", yaml_path.c_str());
  const std::filesystem::path yaml_file(yaml_path);
  const std::string image = yaml_file.stem().string() + ".pgm";
  const std::string note = commented(comment);
  std::string pgm = "P5\n" + note + std::to_string(map.width()) + " " + std::to_string(map.height()) + "\n255\n";
  pgm.reserve(pgm.size() + map.cell_count());
  for (int image_row = 0; image_row < map.height(); ++image_row) {
    const int row = map.height() - 1 - image_row;
    for (int col = 0; col < map.width(); ++col) {
      const std::int8_t v = map.at(col, row);
      pgm.push_back(v >= 65 ? '\0' : (v >= 0 && v <= 19) ? '\xfe' : '\xcd');
    }
  }
  char body[400];
  std::snprintf(body, sizeof body,
                "image: %s\nresolution: %.12g\norigin: [%.12g, %.12g, %.12g]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n",
                image.c_str(), map.resolution_m(), map.origin_x_m(), map.origin_y_m(), map.origin_yaw_rad());
  const std::filesystem::path image_path = yaml_file.parent_path() / image;
  if (Status s = write_whole_file(image_path.string(), pgm); !s) return s;
  return write_whole_file(yaml_path, note + body);
}

}  // namespace sen3bot::nav
