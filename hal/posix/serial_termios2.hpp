#pragma once
// Private to hal/posix: the bridge between the <termios.h> world (serial.cpp, pty.cpp) and
// the <asm/termbits.h> world (serial_termios2.cpp). The two headers both define struct
// termios and cannot share a translation unit, so only plain integers cross this line.
#include <cstdint>

namespace sen3bot::hal::posix {

// The four flag words plus VMIN/VTIME. glibc on Linux hands these words to the kernel
// unchanged (its tcsetattr copies them), so <termios.h> and <asm/termbits.h> agree on
// every bit and either side may interpret them.
struct LineFlags {
  std::uint32_t iflag = 0;
  std::uint32_t oflag = 0;
  std::uint32_t cflag = 0;
  std::uint32_t lflag = 0;
  std::uint8_t vmin = 0;
  std::uint8_t vtime = 0;
};

struct LineState {
  LineFlags flags;
  std::uint32_t input_baud = 0;
  std::uint32_t output_baud = 0;
};

// True when the platform has TCGETS2/TCSETS2 and BOTHER (every Linux target we build for).
bool termios2_available() noexcept;

// One TCSETS2: the given flags (their speed bits are replaced), VMIN/VTIME, and BOTHER with
// baud in both directions. Other control characters keep their current values.
// Returns 0 or an errno value.
int termios2_apply(int fd, const LineFlags& flags, std::uint32_t baud) noexcept;

// TCGETS2: flags and the numeric rates. On a pty master this is the slave's termios.
// Returns 0 or an errno value.
int termios2_read(int fd, LineState& state) noexcept;

}  // namespace sen3bot::hal::posix
