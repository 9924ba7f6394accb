#pragma once
#include <cstddef>

namespace sen3bot::mem {

// Data written by different threads is kept this far apart to avoid false sharing. 64 B is the
// line size of x86-64 and of the Raspberry Pi's Cortex-A53/A72/A76. We do not use
// std::hardware_destructive_interference_size: its value depends on -mtune, so GCC warns
// when it is used in a header (the layout could differ between translation units).
inline constexpr std::size_t kCacheLineBytes = 64;

}  // namespace sen3bot::mem
