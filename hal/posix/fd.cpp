#include <unistd.h>

#include "sen3bot/hal/fd.hpp"

namespace sen3bot::hal {

void UniqueFd::reset(int fd) noexcept {
  // Linux releases the descriptor even when close() reports EINTR, so never retry.
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
}

}  // namespace sen3bot::hal
