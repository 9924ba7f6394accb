#include "sen3bot/nav/map.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace sen3bot::nav {

OccupancyMap::OccupancyMap(int width, int height, double resolution_m, double origin_x_m,
                           double origin_y_m, double origin_yaw_rad)
    : geometry_(width, height, resolution_m, origin_x_m, origin_y_m, origin_yaw_rad),
      cells_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0) {}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front())) != 0) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back())) != 0) s.remove_suffix(1);
  return s;
}

std::string_view unquote(std::string_view s) {
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) {
    return s.substr(1, s.size() - 2);
  }
  return s;
}

// Strips a '#' comment that is not inside quotes.
std::string_view strip_comment(std::string_view line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#') {
      return line.substr(0, i);
    }
  }
  return line;
}

bool parse_double(std::string_view text, double& out) {
  text = trim(text);
  if (text.empty()) return false;
  if (text.front() == '+') text.remove_prefix(1);
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, out);
  return ec == std::errc() && ptr == end && std::isfinite(out);
}

Error key_error(std::string_view source, int line, std::string_view key, const char* what) {
  return Error::format(Errc::config, "%.*s:%d: key '%.*s': %s", static_cast<int>(source.size()),
                       source.data(), line, static_cast<int>(key.size()), key.data(), what);
}

}  // namespace

Result<MapYaml> parse_map_yaml(std::string_view text, std::string_view source) {
  MapYaml yaml;
  bool have_image = false;
  bool have_resolution = false;
  bool have_origin = false;
  bool have_occupied = false;
  bool have_free = false;
  int line_number = 0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t eol = text.find('\n', pos);
    std::string_view line = text.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
    pos = eol == std::string_view::npos ? text.size() + 1 : eol + 1;
    ++line_number;
    line = trim(strip_comment(line));
    if (line.empty() || line == "---") continue;
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos) {
      return Error::format(Errc::config, "%.*s:%d: expected 'key: value', got '%.*s'",
                           static_cast<int>(source.size()), source.data(), line_number,
                           static_cast<int>(std::min<std::size_t>(line.size(), 60)), line.data());
    }
    const std::string_view key = trim(line.substr(0, colon));
    const std::string_view value = trim(line.substr(colon + 1));
    if (value.empty()) return key_error(source, line_number, key, "has no value");
    if (key == "image") {
      const std::string_view path = unquote(value);
      if (path.empty()) return key_error(source, line_number, key, "is empty");
      yaml.image.assign(path);
      have_image = true;
    } else if (key == "resolution") {
      if (!parse_double(value, yaml.resolution_m) || yaml.resolution_m <= 0.0) {
        return key_error(source, line_number, key, "must be a number > 0 (metres per cell)");
      }
      have_resolution = true;
    } else if (key == "origin") {
      if (value.size() < 2 || value.front() != '[' || value.back() != ']') {
        return key_error(source, line_number, key, "must be a list [x, y, yaw]");
      }
      std::string_view items = value.substr(1, value.size() - 2);
      double numbers[3] = {};
      int count = 0;
      while (true) {
        const std::size_t comma = items.find(',');
        const std::string_view item = items.substr(0, comma);
        if (count == 3 || !parse_double(item, numbers[count])) {
          return key_error(source, line_number, key, "must hold exactly three numbers [x, y, yaw]");
        }
        ++count;
        if (comma == std::string_view::npos) break;
        items.remove_prefix(comma + 1);
      }
      if (count != 3) return key_error(source, line_number, key, "must hold exactly three numbers [x, y, yaw]");
      yaml.origin_x_m = numbers[0];
      yaml.origin_y_m = numbers[1];
      yaml.origin_yaw_rad = numbers[2];
      have_origin = true;
    } else if (key == "occupied_thresh" || key == "free_thresh") {
      double v = 0.0;
      if (!parse_double(value, v) || v < 0.0 || v > 1.0) {
        return key_error(source, line_number, key, "must be a number in [0, 1]");
      }
      (key == "occupied_thresh" ? yaml.occupied_thresh : yaml.free_thresh) = v;
      (key == "occupied_thresh" ? have_occupied : have_free) = true;
    } else if (key == "negate") {
      const std::string_view v = unquote(value);
      if (v == "0" || v == "false") {
        yaml.negate = false;
      } else if (v == "1" || v == "true") {
        yaml.negate = true;
      } else {
        return key_error(source, line_number, key, "must be 0, 1, true or false");
      }
    } else if (key == "mode") {
      const std::string_view v = unquote(value);
      if (v == "trinary") {
        yaml.mode = MapMode::trinary;
      } else if (v == "scale") {
        yaml.mode = MapMode::scale;
      } else if (v == "raw") {
        yaml.mode = MapMode::raw;
      } else {
        return key_error(source, line_number, key, "must be trinary, scale or raw");
      }
    } else {
      return key_error(source, line_number, key, "is not a map key (image, resolution, origin, "
                                                 "occupied_thresh, free_thresh, negate, mode)");
    }
  }
  const auto missing = [&](const char* key) {
    return Error::format(Errc::config, "%.*s: required key '%s' is missing",
                         static_cast<int>(source.size()), source.data(), key);
  };
  if (!have_image) return missing("image");
  if (!have_resolution) return missing("resolution");
  if (!have_origin) return missing("origin");
  (void)have_occupied;
  (void)have_free;
  if (yaml.free_thresh >= yaml.occupied_thresh) {
    return Error::format(Errc::config, "%.*s: free_thresh %g must be below occupied_thresh %g",
                         static_cast<int>(source.size()), source.data(), yaml.free_thresh,
                         yaml.occupied_thresh);
  }
  return yaml;
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
  auto yaml = parse_map_yaml(*text, yaml_path);
  if (!yaml) return yaml.error();
  std::filesystem::path image_path(yaml->image);
  if (image_path.is_relative()) image_path = std::filesystem::path(yaml_path).parent_path() / image_path;
  const std::string image_name = image_path.string();
  auto bytes = read_whole_file(image_name, 2 * kMaxMapCells + 4096);
  if (!bytes) {
    return Error::format(bytes.error().code(), "%s: key 'image': %s", yaml_path.c_str(), bytes.error().c_str());
  }
  auto image = parse_pgm(*bytes, image_name);
  if (!image) return image.error();
  return occupancy_from_image(*image, *yaml);
}

}  // namespace sen3bot::nav
