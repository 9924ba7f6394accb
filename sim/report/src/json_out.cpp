#include "sen3bot/sim/report/json_out.hpp"

#include <cmath>

namespace sen3bot::sim::report {

std::string json_quoted(std::string_view s) {
  std::string o = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
      o += buf;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

void write_json_string(std::FILE* f, std::string_view s) { std::fputs(json_quoted(s).c_str(), f); }

void write_json_number(std::FILE* f, double v, const char* format) {
  if (std::isfinite(v)) std::fprintf(f, format, v);
  else std::fputs("null", f);
}

}  // namespace sen3bot::sim::report
