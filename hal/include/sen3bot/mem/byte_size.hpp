#pragma once
// Byte sizes in configuration files: "4096", "4096 B", "64KiB", "1 MiB", "2GiB". Only binary
// (IEC) units are accepted: "KB"/"MB" are ambiguous (1000 or 1024?), so they are rejected with
// a message naming the accepted units rather than guessed.
#include <cstddef>
#include <limits>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::mem {

inline constexpr std::size_t kKiB = std::size_t{1} << 10;
inline constexpr std::size_t kMiB = std::size_t{1} << 20;
inline constexpr std::size_t kGiB = std::size_t{1} << 30;

// Errors are Errc::config and quote the text.
inline Result<std::size_t> parse_byte_size(std::string_view text) noexcept {
  constexpr int kQuoteMax = 48;  // longest quoted excerpt of the input, to fit Error's buffer
  const auto quoted_length = [&] {
    return static_cast<int>(text.size() < kQuoteMax ? text.size() : kQuoteMax);
  };
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  if (text.empty()) return Error(Errc::config, "byte size is empty");

  std::size_t pos = 0;
  std::size_t number = 0;
  for (; pos < text.size() && text[pos] >= '0' && text[pos] <= '9'; ++pos) {
    const auto digit = static_cast<std::size_t>(text[pos] - '0');
    if (number > (std::numeric_limits<std::size_t>::max() - digit) / 10) {
      return Error::format(Errc::config, "byte size '%.*s' is too large", quoted_length(), text.data());
    }
    number = number * 10 + digit;
  }
  if (pos == 0 || (pos < text.size() && (text[pos] == '.' || text[pos] == ','))) {
    return Error::format(Errc::config,
                         "byte size '%.*s': expected a whole number of bytes with an optional "
                         "unit B, KiB, MiB or GiB",
                         quoted_length(), text.data());
  }
  while (pos < text.size() && is_space(text[pos])) ++pos;
  const std::string_view unit = text.substr(pos);

  std::size_t multiplier = 0;
  if (unit.empty() || unit == "B") {
    multiplier = 1;
  } else if (unit == "KiB") {
    multiplier = kKiB;
  } else if (unit == "MiB") {
    multiplier = kMiB;
  } else if (unit == "GiB") {
    multiplier = kGiB;
  } else {
    return Error::format(Errc::config, "byte size '%.*s': unknown unit '%.*s' (use B, KiB, MiB or GiB)",
                         quoted_length(), text.data(),
                         static_cast<int>(unit.size() < 16 ? unit.size() : 16), unit.data());
  }
  if (number > std::numeric_limits<std::size_t>::max() / multiplier) {
    return Error::format(Errc::config, "byte size '%.*s' is too large", quoted_length(), text.data());
  }
  return number * multiplier;
}

}  // namespace sen3bot::mem
