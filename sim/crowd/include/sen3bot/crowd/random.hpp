#pragma once
// Random draws that are the same on every platform and standard library, so a seeded scene or
// layout is the same everywhere: std::mt19937_64 is specified bit for bit, the std
// distributions (uniform_real_distribution, normal_distribution) are not.
#include <cmath>
#include <numbers>
#include <random>

namespace sen3bot::crowd {

// [0, 1) from the top 53 bits of one draw.
[[nodiscard]] inline double unit_uniform(std::mt19937_64& rng) noexcept {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// Uniform over [lo, hi) (hi itself only by rounding); one draw.
[[nodiscard]] inline double uniform(std::mt19937_64& rng, double lo, double hi) noexcept {
  return lo + (hi - lo) * unit_uniform(rng);
}

// A standard normal value by Box-Muller (two draws, the cosine half of the pair). log, sqrt and
// cos are the C library's: glibc rounds them correctly in practice, another libm may differ
// in the last bit.
[[nodiscard]] inline double standard_normal(std::mt19937_64& rng) noexcept {
  const double u1 = 1.0 - unit_uniform(rng);  // (0, 1]: the log stays finite
  const double u2 = unit_uniform(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace sen3bot::crowd
