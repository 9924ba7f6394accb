#pragma once
// Private to hal/posix: turning errno into the HAL's error values without allocating.
#include <cstddef>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal::posix {

// "<formatted context>: <strerror(errnum)>", built in the Error's fixed buffer.
[[gnu::format(printf, 3, 4)]] Error errno_error(Errc code, int errnum, const char* fmt, ...) noexcept;

// strerror_r text for errnum (buffer used only if the C library needs it).
const char* errno_text(int errnum, char* buffer, std::size_t size) noexcept;

// Category for an errno from read/write/send/recv on a device or a connected socket:
// EAGAIN -> would_block; a vanished device or peer (EIO, ENODEV, ENXIO, EPIPE, ECONNRESET,
// ...) -> disconnected; anything else -> io.
Errc classify_io_errno(int errnum) noexcept;

// Category for an errno from open()/connect()/bind(): ENOENT/ENODEV/ENXIO -> not_found,
// EACCES/EPERM -> permission, anything else -> io.
Errc classify_open_errno(int errnum) noexcept;

}  // namespace sen3bot::hal::posix
