#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

#include "posix_error.hpp"
#include "sen3bot/hal/pty.hpp"
#include "serial_internal.hpp"

namespace sen3bot::hal {

namespace {

constexpr int kSlaveOpenFlags = O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC;

// TIOCGPTPEER (Linux 4.13) opens the slave through the master, immune to a path that was
// replaced under us; fall back to the path on older kernels.
int open_slave(int master_fd, const char* slave_path) {
#ifdef TIOCGPTPEER
  const int fd = ::ioctl(master_fd, TIOCGPTPEER, kSlaveOpenFlags);
  if (fd >= 0) return fd;
#else
  (void)master_fd;
#endif
  return ::open(slave_path, kSlaveOpenFlags);
}

}  // namespace

PtyPair::PtyPair(UniqueFd master, UniqueFd slave_keeper, std::string slave_path)
    : master_(std::move(master)),
      slave_keeper_(std::move(slave_keeper)),
      slave_path_(std::move(slave_path)),
      name_("pty master of " + slave_path_) {}

PtyPair::~PtyPair() {
  if (link_path_.empty()) return;
  // Remove the link only while it still points at our slave: another emulator may have
  // taken the name over since.
  char target[64] = {};
  const ssize_t n = ::readlink(link_path_.c_str(), target, sizeof target - 1);
  if (n > 0 && std::string_view(target, static_cast<std::size_t>(n)) == slave_path_) ::unlink(link_path_.c_str());
}

Result<std::unique_ptr<PtyPair>> PtyPair::open(PtyOptions options) {
  UniqueFd master(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!master) {
    const int err = errno;
    return posix::errno_error(posix::classify_open_errno(err), err, "posix_openpt");
  }
  const int flags = ::fcntl(master.get(), F_GETFL);
  if (flags < 0 || ::fcntl(master.get(), F_SETFL, flags | O_NONBLOCK) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "pty master: fcntl(O_NONBLOCK)");
  }
  if (::grantpt(master.get()) != 0 || ::unlockpt(master.get()) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "pty master: grantpt/unlockpt");
  }
  char path[64] = {};
  if (const int err = ::ptsname_r(master.get(), path, sizeof path); err != 0) {
    return posix::errno_error(Errc::io, err, "pty master: ptsname_r");
  }
  // tcsetattr on a Linux master sets the slave's termios.
  termios t{};
  if (::tcgetattr(master.get(), &t) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "pty %s: tcgetattr", path);
  }
  ::cfmakeraw(&t);
  t.c_cflag |= CLOCAL;
  if (::tcsetattr(master.get(), TCSANOW, &t) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "pty %s: tcsetattr raw", path);
  }
  UniqueFd keeper;
  if (options.keep_slave_open) {
    keeper.reset(open_slave(master.get(), path));
    if (!keeper) {
      const int err = errno;
      return posix::errno_error(Errc::io, err, "pty %s: opening the slave", path);
    }
  }
  return std::unique_ptr<PtyPair>(new PtyPair(std::move(master), std::move(keeper), path));
}

Result<std::size_t> PtyPair::read(std::span<std::uint8_t> out) {
  if (out.empty()) return std::size_t{0};
  for (;;) {
    const ssize_t n = ::read(master_.get(), out.data(), out.size());
    if (n >= 0) return static_cast<std::size_t>(n);
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::size_t{0};
    if (err == EIO) {
      return Error::format(Errc::disconnected, "%s: no process has the slave open (EIO)", name_.c_str());
    }
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: read", name_.c_str());
  }
}

Result<std::size_t> PtyPair::write(std::span<const std::uint8_t> data) {
  if (data.empty()) return std::size_t{0};
  for (;;) {
    const ssize_t n = ::write(master_.get(), data.data(), data.size());
    if (n >= 0) return static_cast<std::size_t>(n);
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::size_t{0};
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: write", name_.c_str());
  }
}

Result<std::uint32_t> PtyPair::slave_baud() const { return posix::query_baud(master_.get(), name_); }

Result<SerialLineSettings> PtyPair::slave_line_settings() const {
  return posix::query_line_settings(master_.get(), name_);
}

Status PtyPair::link_slave(std::string_view link_path) {
  std::string link(link_path);
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (::symlink(slave_path_.c_str(), link.c_str()) == 0) {
      if (!link_path_.empty() && link_path_ != link) ::unlink(link_path_.c_str());
      link_path_ = std::move(link);
      return {};
    }
    const int err = errno;
    struct stat info {};
    // Only ever replace a symlink (left by an emulator that crashed), never a real file.
    if (err != EEXIST || attempt > 0 || ::lstat(link.c_str(), &info) != 0 || !S_ISLNK(info.st_mode) ||
        ::unlink(link.c_str()) != 0) {
      return posix::errno_error(posix::classify_open_errno(err), err, "symlink %s -> %s", link.c_str(),
                                slave_path_.c_str());
    }
  }
  return Error::format(Errc::io, "symlink %s -> %s: could not replace the existing link", link.c_str(),
                       slave_path_.c_str());
}

}  // namespace sen3bot::hal
