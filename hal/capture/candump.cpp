#include "sen3bot/hal/candump.hpp"

#include <cstdio>

namespace sen3bot::hal {

namespace {

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Seconds whose nanoseconds still fit in 63 bits.
constexpr std::int64_t kMaxSeconds = 9'000'000'000;

Error bad(std::size_t column, const char* what) {
  return Error::format(Errc::protocol, "candump line, column %zu: %s", column + 1, what);
}

}  // namespace

Result<CandumpLine> parse_candump_line(std::string_view line) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
    line.remove_suffix(1);
  CandumpLine out;
  std::size_t i = 0;
  // (seconds.fraction)
  if (i >= line.size() || line[i] != '(') return bad(i, "expected '(' and the time");
  ++i;
  std::int64_t seconds = 0;
  std::size_t digits = 0;
  for (; i < line.size() && line[i] >= '0' && line[i] <= '9'; ++i, ++digits) {
    if (digits >= 10) return bad(i, "the time's seconds have more than 10 digits");
    seconds = seconds * 10 + (line[i] - '0');
  }
  if (digits == 0) return bad(i, "expected the time's seconds");
  if (seconds > kMaxSeconds) return bad(i - 1, "the time is past the year 2255");
  if (i >= line.size() || line[i] != '.') return bad(i, "expected '.' in the time");
  ++i;
  std::int64_t fraction_ns = 0;
  std::int64_t scale = 100'000'000;
  digits = 0;
  for (; i < line.size() && line[i] >= '0' && line[i] <= '9'; ++i, ++digits) {
    if (digits >= 9) return bad(i, "the time's fraction has more than 9 digits");
    fraction_ns += (line[i] - '0') * scale;
    scale /= 10;
  }
  if (digits == 0) return bad(i, "expected the time's fraction");
  if (i >= line.size() || line[i] != ')') return bad(i, "expected ')' after the time");
  ++i;
  out.unix_ns = seconds * 1'000'000'000 + fraction_ns;
  // interface
  if (i >= line.size() || line[i] != ' ') return bad(i, "expected a space before the interface");
  ++i;
  std::size_t name = 0;
  for (; i < line.size() && line[i] != ' '; ++i) {
    if (line[i] < 0x21 || line[i] > 0x7E || line[i] == '#')
      return bad(i, "the interface's name has a control character or '#'");
    if (name >= CandumpLine::kMaxInterface) return bad(i, "the interface's name is longer than 15 characters");
    out.interface[name++] = line[i];
  }
  if (name == 0) return bad(i, "expected the interface's name");
  if (i >= line.size()) return bad(i, "expected a space and the frame after the interface");
  ++i;
  // id#data
  const std::size_t id_start = i;
  std::uint32_t id = 0;
  for (; i < line.size() && line[i] != '#'; ++i) {
    const int v = hex_value(line[i]);
    if (v < 0) return bad(i, "the id is not hexadecimal");
    if (i - id_start >= 8) return bad(i, "the id has more than 8 hex digits");
    id = id << 4 | static_cast<std::uint32_t>(v);
  }
  const std::size_t id_digits = i - id_start;
  if (i >= line.size()) return bad(i, "expected '#' after the id");
  if (id_digits == 3) {
    if (id > CanFrame::kMaxStandardId) return bad(id_start, "a 3-digit id above 0x7FF");
    out.frame.id = id;
  } else if (id_digits == 8) {
    out.frame.extended = true;
    if ((id & can_error::kFlag) != 0) {
      out.error_frame = true;
      id &= ~can_error::kFlag;
    }
    if (id > CanFrame::kMaxExtendedId) return bad(id_start, "an 8-digit id with bits above 29 other than the error flag");
    out.frame.id = id;
  } else {
    return bad(id_start, "the id needs 3 hex digits (standard) or 8 (extended)");
  }
  ++i;  // '#'
  if (i < line.size() && line[i] == '#')
    return Error::format(Errc::not_supported, "candump line, column %zu: a CAN FD frame ('##'); the bus is classic CAN",
                         i + 1);
  if (i < line.size() && (line[i] == 'R' || line[i] == 'r')) {
    if (out.error_frame) return bad(i, "an error frame cannot be a remote request");
    out.frame.rtr = true;
    ++i;
    if (i < line.size()) {
      if (line[i] < '0' || line[i] > '8' || i + 1 != line.size()) return bad(i, "a remote request's length is one digit 0..8");
      out.frame.dlc = static_cast<std::uint8_t>(line[i] - '0');
    }
    return out;
  }
  std::size_t bytes = 0;
  while (i < line.size()) {
    if (line[i] == '.') {  // cansend's byte separator
      ++i;
      continue;
    }
    if (bytes >= CanFrame::kMaxDataBytes) return bad(i, "more than 8 data bytes");
    if (i + 1 >= line.size()) return bad(i, "an odd number of data hex digits");
    const int hi = hex_value(line[i]);
    const int lo = hex_value(line[i + 1]);
    if (hi < 0 || lo < 0) return bad(hi < 0 ? i : i + 1, "the data is not hexadecimal");
    out.frame.data[bytes++] = static_cast<std::uint8_t>(hi << 4 | lo);
    i += 2;
  }
  out.frame.dlc = static_cast<std::uint8_t>(bytes);
  return out;
}

std::size_t format_candump_line(const CandumpLine& line, std::span<char> out) noexcept {
  const CanFrame& f = line.frame;
  if (!f.validate() || line.unix_ns < 0 || line.interface[0] == '\0' || (line.error_frame && !f.extended)) return 0;
  for (std::size_t k = 0; k <= CandumpLine::kMaxInterface; ++k) {
    const char c = line.interface[k];
    if (c == '\0') break;
    if (k == CandumpLine::kMaxInterface || c < 0x21 || c > 0x7E || c == '#') return 0;
  }
  std::array<char, kMaxCandumpLine + 8> text{};
  const auto seconds = static_cast<long long>(line.unix_ns / 1'000'000'000);
  const auto micros = static_cast<long long>(line.unix_ns % 1'000'000'000 / 1000);
  int n = 0;
  const std::uint32_t id = line.error_frame ? (f.id | can_error::kFlag) : f.id;
  if (f.extended)
    n = std::snprintf(text.data(), text.size(), "(%lld.%06lld) %s %08X#", seconds, micros, line.interface.data(),
                      static_cast<unsigned>(id));
  else
    n = std::snprintf(text.data(), text.size(), "(%lld.%06lld) %s %03X#", seconds, micros, line.interface.data(),
                      static_cast<unsigned>(id));
  if (n <= 0) return 0;
  auto len = static_cast<std::size_t>(n);
  constexpr char kHex[] = "0123456789ABCDEF";
  if (f.rtr) {
    text[len++] = 'R';
    if (f.dlc > 0) text[len++] = static_cast<char>('0' + f.dlc);
  } else {
    for (std::size_t b = 0; b < f.dlc; ++b) {
      text[len++] = kHex[f.data[b] >> 4];
      text[len++] = kHex[f.data[b] & 0xF];
    }
  }
  text[len++] = '\n';
  if (len > out.size()) return 0;
  for (std::size_t k = 0; k < len; ++k) out[k] = text[k];
  return len;
}

}  // namespace sen3bot::hal
