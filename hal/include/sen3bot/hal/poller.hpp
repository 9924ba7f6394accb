#pragma once
// Waiting on several descriptors at once with poll(2), over a fixed-capacity set: nothing
// is allocated after construction, so an I/O thread can wait in its steady state.
#include <poll.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

enum class PollInterest : std::uint8_t {
  readable = 1,
  writable = 2,
  readable_or_writable = 3,
};

struct PollEvent {
  int fd = -1;
  std::uint64_t tag = 0;  // what the caller passed to add(), e.g. an index or a pointer
  bool readable = false;
  bool writable = false;
  bool hangup = false;   // POLLHUP: the peer or device is gone (reads will say disconnected)
  bool error = false;    // POLLERR
  bool invalid = false;  // POLLNVAL: the fd was closed without being removed
};

class Poller {
 public:
  static constexpr std::size_t kCapacity = 32;

  // fd must be >= 0 and not already present (streams without an fd are polled by reading).
  // Errc::capacity when kCapacity descriptors are already registered.
  Status add(int fd, std::uint64_t tag, PollInterest interest = PollInterest::readable);
  Status set_interest(int fd, PollInterest interest);
  Status remove(int fd);
  [[nodiscard]] bool contains(int fd) const noexcept;
  [[nodiscard]] std::size_t size() const noexcept { return count_; }

  // Blocks up to timeout_ms (-1 = forever, 0 = just look) and returns the descriptors that
  // are ready, HUP/ERR/NVAL included; empty on timeout or when a signal interrupted the
  // wait. The span stays valid until the next call to wait/add/remove.
  Result<std::span<const PollEvent>> wait(int timeout_ms);

 private:
  [[nodiscard]] std::size_t index_of(int fd) const noexcept;

  std::array<pollfd, kCapacity> fds_{};
  std::array<std::uint64_t, kCapacity> tags_{};
  std::array<PollEvent, kCapacity> ready_{};
  std::size_t count_ = 0;
};

}  // namespace sen3bot::hal
