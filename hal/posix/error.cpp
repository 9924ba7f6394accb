#include <cstring>

#include "sen3bot/hal/result.hpp"

namespace sen3bot {

std::string_view to_string(Errc code) noexcept {
  switch (code) {
    case Errc::would_block: return "would_block";
    case Errc::timeout: return "timeout";
    case Errc::disconnected: return "disconnected";
    case Errc::io: return "io";
    case Errc::invalid_argument: return "invalid_argument";
    case Errc::not_supported: return "not_supported";
    case Errc::permission: return "permission";
    case Errc::protocol: return "protocol";
    case Errc::capacity: return "capacity";
    case Errc::not_found: return "not_found";
    case Errc::config: return "config";
  }
  return "unknown";
}

Error Error::from_errno(Errc code, std::string_view what, int errnum) noexcept {
  char reason[96];
  // GNU strerror_r returns a pointer that may or may not be the buffer.
  const char* text = strerror_r(errnum, reason, sizeof reason);
  return Error::format(code, "%.*s: %s", static_cast<int>(what.size()), what.data(), text);
}

}  // namespace sen3bot
