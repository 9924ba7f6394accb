#include "sen3bot/mem/byte_size.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

namespace sen3bot::mem {
namespace {

TEST(ByteSizeTest, ParsesPlainNumbersAndBinaryUnits) {
  const std::pair<std::string_view, std::size_t> cases[] = {
      {"0", 0},
      {"4096", 4096},
      {"4096B", 4096},
      {"4096 B", 4096},
      {"64KiB", 64 * 1024},
      {"64 KiB", 64 * 1024},
      {"1MiB", 1024 * 1024},
      {"16 MiB", 16u * 1024 * 1024},
      {"2GiB", 2ULL * 1024 * 1024 * 1024},
      {"  64KiB\n", 64 * 1024},
      {"\t1 MiB ", 1024 * 1024},
      {"007", 7},
  };
  for (const auto& [text, expected] : cases) {
    const auto parsed = parse_byte_size(text);
    ASSERT_TRUE(parsed.ok()) << "'" << text << "': " << parsed.error().message();
    EXPECT_EQ(*parsed, expected) << text;
  }
}

TEST(ByteSizeTest, RejectsWithClearMessages) {
  const std::pair<std::string_view, std::string_view> cases[] = {
      {"", "byte size is empty"},
      {"   ", "byte size is empty"},
      {"KiB", "byte size 'KiB': expected a whole number of bytes with an optional unit B, KiB, MiB or GiB"},
      {"-5", "byte size '-5': expected a whole number of bytes with an optional unit B, KiB, MiB or GiB"},
      {"1.5MiB", "byte size '1.5MiB': expected a whole number of bytes with an optional unit B, KiB, MiB or GiB"},
      {"64KB", "byte size '64KB': unknown unit 'KB' (use B, KiB, MiB or GiB)"},
      {"64 kib", "byte size '64 kib': unknown unit 'kib' (use B, KiB, MiB or GiB)"},
      {"1MB", "byte size '1MB': unknown unit 'MB' (use B, KiB, MiB or GiB)"},
      {"64KiBs", "byte size '64KiBs': unknown unit 'KiBs' (use B, KiB, MiB or GiB)"},
      {"64 KiB x", "byte size '64 KiB x': unknown unit 'KiB x' (use B, KiB, MiB or GiB)"},
      {"99999999999999999999999", "byte size '99999999999999999999999' is too large"},
      {"17179869184GiB", "byte size '17179869184GiB' is too large"},
  };
  for (const auto& [text, message] : cases) {
    const auto parsed = parse_byte_size(text);
    ASSERT_FALSE(parsed.ok()) << "'" << text << "' parsed as " << *parsed;
    EXPECT_EQ(parsed.error().code(), Errc::config);
    EXPECT_EQ(parsed.error().message(), message);
  }
}

TEST(ByteSizeTest, LargestValuesAtTheEdge) {
  const std::size_t max = std::numeric_limits<std::size_t>::max();
  const auto exact = parse_byte_size(std::to_string(max));
  ASSERT_TRUE(exact.ok());
  EXPECT_EQ(*exact, max);
  EXPECT_FALSE(parse_byte_size(std::to_string(max) + "0").ok());
  const auto gib = parse_byte_size(std::to_string(max / kGiB) + "GiB");
  ASSERT_TRUE(gib.ok());
  EXPECT_EQ(*gib, max / kGiB * kGiB);
  EXPECT_FALSE(parse_byte_size(std::to_string(max / kGiB + 1) + "GiB").ok());
}

TEST(ByteSizeTest, LongInputIsQuotedTruncated) {
  const std::string text = std::string(200, '9');
  const auto parsed = parse_byte_size(text);
  ASSERT_FALSE(parsed.ok());
  EXPECT_EQ(parsed.error().message(), "byte size '" + std::string(48, '9') + "' is too large");
}

}  // namespace
}  // namespace sen3bot::mem
