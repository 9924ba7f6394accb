// Non-standard baud rates through termios2 + BOTHER. This file must include the kernel's
// <asm/termbits.h> and never <termios.h>: both define struct termios.
#include <asm/termbits.h>
#include <sys/ioctl.h>

#include <cerrno>

#include "serial_termios2.hpp"

namespace sen3bot::hal::posix {

#if defined(TCGETS2) && defined(TCSETS2) && defined(BOTHER)

bool termios2_available() noexcept { return true; }

namespace {
int ioctl_retry(int fd, unsigned long request, termios2* t) noexcept {
  for (;;) {
    if (::ioctl(fd, request, t) == 0) return 0;
    if (errno != EINTR) return errno;
  }
}
}  // namespace

int termios2_apply(int fd, const LineFlags& flags, std::uint32_t baud) noexcept {
  termios2 t{};
  if (const int err = ioctl_retry(fd, TCGETS2, &t); err != 0) return err;
  t.c_iflag = flags.iflag;
  t.c_oflag = flags.oflag;
  t.c_lflag = flags.lflag;
  // BOTHER in both the output (CBAUD) and input (CIBAUD) fields: the kernel then takes the
  // numeric c_ospeed / c_ispeed instead of a Bxxx code.
  t.c_cflag = (flags.cflag & ~static_cast<tcflag_t>(CBAUD | CIBAUD)) | BOTHER |
              (static_cast<tcflag_t>(BOTHER) << IBSHIFT);
  t.c_ispeed = baud;
  t.c_ospeed = baud;
  t.c_cc[VMIN] = flags.vmin;
  t.c_cc[VTIME] = flags.vtime;
  return ioctl_retry(fd, TCSETS2, &t);
}

int termios2_read(int fd, LineState& state) noexcept {
  termios2 t{};
  if (const int err = ioctl_retry(fd, TCGETS2, &t); err != 0) return err;
  state.flags.iflag = t.c_iflag;
  state.flags.oflag = t.c_oflag;
  state.flags.cflag = t.c_cflag;
  state.flags.lflag = t.c_lflag;
  state.flags.vmin = t.c_cc[VMIN];
  state.flags.vtime = t.c_cc[VTIME];
  state.input_baud = t.c_ispeed;
  state.output_baud = t.c_ospeed;
  return 0;
}

#else  // a platform without termios2: only the Bxxx rates are available

bool termios2_available() noexcept { return false; }
int termios2_apply(int, const LineFlags&, std::uint32_t) noexcept { return ENOTSUP; }
int termios2_read(int, LineState&) noexcept { return ENOTSUP; }

#endif

}  // namespace sen3bot::hal::posix
