#pragma once
// Whether one condition makes an event (a task's late start, say) more frequent than a control
// measured beside it in the same run. A shared machine makes the count of such events vary from
// run to run, so a test that asserts "none" fails at random; a test that compares against a
// control interleaved with the condition fails only when the condition itself costs something.
//
// Events are treated as a Poisson process: given n = a + b events in all, the number that fall
// in the condition's exposure is binomial with p = exposure_a / (exposure_a + exposure_b) when
// the condition changes nothing. The p-value is that binomial's upper tail at a. Count events
// that happen independently (late starts, not the releases one long stall skips), or the
// clusters make the tail far too small.
#include <cmath>
#include <cstdint>

namespace sen3bot::testing {

// P(X >= a) for X ~ Binomial(a + b, exposure_a / (exposure_a + exposure_b)).
inline double excess_p_value(std::uint64_t a, double exposure_a, std::uint64_t b, double exposure_b) {
  const std::uint64_t n = a + b;
  if (a == 0 || exposure_a <= 0.0) return 1.0;
  if (exposure_b <= 0.0) return 0.0;
  const double p = exposure_a / (exposure_a + exposure_b);
  const double log_p = std::log(p), log_q = std::log1p(-p);
  double tail = 0.0;
  for (std::uint64_t k = a; k <= n; ++k) {
    const double log_term = std::lgamma(static_cast<double>(n) + 1.0) - std::lgamma(static_cast<double>(k) + 1.0) -
                            std::lgamma(static_cast<double>(n - k) + 1.0) + static_cast<double>(k) * log_p +
                            static_cast<double>(n - k) * log_q;
    tail += std::exp(log_term);
  }
  return tail > 1.0 ? 1.0 : tail;
}

}  // namespace sen3bot::testing
