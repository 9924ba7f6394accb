#include "posix_error.hpp"

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace sen3bot::hal::posix {

Error errno_error(Errc code, int errnum, const char* fmt, ...) noexcept {
  char context[Error::kMessageCapacity];
  std::va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(context, sizeof context, fmt, args);
  va_end(args);
  const std::size_t length =
      n < 0 ? 0 : (static_cast<std::size_t>(n) < sizeof context ? static_cast<std::size_t>(n) : sizeof context - 1);
  return Error::from_errno(code, std::string_view(context, length), errnum);
}

const char* errno_text(int errnum, char* buffer, std::size_t size) noexcept {
  // GNU strerror_r (glibc with _GNU_SOURCE, which g++ always defines) returns the text.
  return ::strerror_r(errnum, buffer, size);
}

Errc classify_io_errno(int errnum) noexcept {
  switch (errnum) {
    case EAGAIN:
#if EWOULDBLOCK != EAGAIN
    case EWOULDBLOCK:
#endif
      return Errc::would_block;
    case EIO:
    case ENODEV:
    case ENXIO:
    case EPIPE:
    case ECONNRESET:
    case ECONNABORTED:
    case ENOTCONN:
    case ESHUTDOWN:
    case ETIMEDOUT:
    case ENETDOWN:
    case ENETUNREACH:
    case EHOSTUNREACH:
    case EBADF:  // the descriptor was closed under us (e.g. after a failed reopen)
      return Errc::disconnected;
    default:
      return Errc::io;
  }
}

Errc classify_open_errno(int errnum) noexcept {
  switch (errnum) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
    case ENOTDIR:
      return Errc::not_found;
    case EACCES:
    case EPERM:
      return Errc::permission;
    default:
      return Errc::io;
  }
}

}  // namespace sen3bot::hal::posix
