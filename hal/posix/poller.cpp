#include <cerrno>

#include "posix_error.hpp"
#include "sen3bot/hal/poller.hpp"

namespace sen3bot::hal {

namespace {
short events_for(PollInterest interest) {
  const auto bits = static_cast<unsigned>(interest);
  short events = 0;
  if ((bits & static_cast<unsigned>(PollInterest::readable)) != 0) events = static_cast<short>(events | POLLIN);
  if ((bits & static_cast<unsigned>(PollInterest::writable)) != 0) events = static_cast<short>(events | POLLOUT);
  return events;
}
}  // namespace

std::size_t Poller::index_of(int fd) const noexcept {
  for (std::size_t i = 0; i < count_; ++i) {
    if (fds_[i].fd == fd) return i;
  }
  return kCapacity;
}

bool Poller::contains(int fd) const noexcept { return index_of(fd) != kCapacity; }

Status Poller::add(int fd, std::uint64_t tag, PollInterest interest) {
  if (fd < 0) return Error::format(Errc::invalid_argument, "poller: fd %d cannot be polled", fd);
  if (contains(fd)) return Error::format(Errc::invalid_argument, "poller: fd %d is already registered", fd);
  if (count_ == kCapacity) {
    return Error::format(Errc::capacity, "poller: all %zu slots in use, cannot add fd %d", kCapacity, fd);
  }
  fds_[count_] = pollfd{fd, events_for(interest), 0};
  tags_[count_] = tag;
  ++count_;
  return {};
}

Status Poller::set_interest(int fd, PollInterest interest) {
  const std::size_t i = index_of(fd);
  if (i == kCapacity) return Error::format(Errc::not_found, "poller: fd %d is not registered", fd);
  fds_[i].events = events_for(interest);
  return {};
}

Status Poller::remove(int fd) {
  const std::size_t i = index_of(fd);
  if (i == kCapacity) return Error::format(Errc::not_found, "poller: fd %d is not registered", fd);
  // Keep the registered entries contiguous for poll(): move the last one into the hole.
  --count_;
  fds_[i] = fds_[count_];
  tags_[i] = tags_[count_];
  return {};
}

Result<std::span<const PollEvent>> Poller::wait(int timeout_ms) {
  const int ready = ::poll(fds_.data(), static_cast<nfds_t>(count_), timeout_ms);
  if (ready < 0) {
    const int err = errno;
    if (err == EINTR) return std::span<const PollEvent>();
    return posix::errno_error(Errc::io, err, "poller: poll over %zu fds", count_);
  }
  std::size_t found = 0;
  for (std::size_t i = 0; i < count_ && found < static_cast<std::size_t>(ready); ++i) {
    const short revents = fds_[i].revents;
    if (revents == 0) continue;
    PollEvent& event = ready_[found++];
    event.fd = fds_[i].fd;
    event.tag = tags_[i];
    event.readable = (revents & POLLIN) != 0;
    event.writable = (revents & POLLOUT) != 0;
    event.hangup = (revents & POLLHUP) != 0;
    event.error = (revents & POLLERR) != 0;
    event.invalid = (revents & POLLNVAL) != 0;
  }
  return std::span<const PollEvent>(ready_.data(), found);
}

}  // namespace sen3bot::hal
