// SocketCAN raw sockets (Linux). Absent AF_CAN support is an expected, reported condition.
// Error frames and receive times come with each read (recvmsg); the transmit queue is CanTxRing.
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <ctime>

#include "posix_error.hpp"
#include "sen3bot/hal/can.hpp"

namespace sen3bot::hal {

namespace {

can_frame to_kernel(const CanFrame& frame) {
  can_frame out{};
  out.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0U) | (frame.rtr ? CAN_RTR_FLAG : 0U);
  out.len = frame.dlc;
  if (!frame.rtr) std::memcpy(out.data, frame.data.data(), frame.dlc);
  return out;
}

CanFrame from_kernel(const can_frame& in) {
  CanFrame frame;
  frame.extended = (in.can_id & CAN_EFF_FLAG) != 0;
  frame.rtr = (in.can_id & CAN_RTR_FLAG) != 0;
  frame.id = in.can_id & (frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  frame.dlc = in.len <= CAN_MAX_DLEN ? in.len : CAN_MAX_DLEN;
  if (!frame.rtr) std::memcpy(frame.data.data(), in.data, frame.dlc);
  return frame;
}

// What the kernel reports: the classes that change the link state, and a transmit timeout
// (counted). Bus errors, lost arbitration and no-ACK come at the bus's error rate and say
// nothing the controller state does not.
constexpr can_err_mask_t kErrorMask = CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;

// The error classes as parse_candump_line gives them: the id without CAN_ERR_FLAG, extended.
CanFrame error_from_kernel(const can_frame& in) {
  CanFrame frame;
  frame.id = in.can_id & CAN_ERR_MASK;
  frame.extended = true;
  frame.dlc = in.len <= CAN_MAX_DLEN ? in.len : CAN_MAX_DLEN;
  std::memcpy(frame.data.data(), in.data, frame.dlc);
  return frame;
}

// The receive time from SO_TIMESTAMPNS (or SO_TIMESTAMP), or -1 without one.
std::int64_t receive_time(msghdr& message) {
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPNS && c->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
      timespec t{};
      std::memcpy(&t, CMSG_DATA(c), sizeof t);
      return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
    }
    if (c->cmsg_type == SCM_TIMESTAMP && c->cmsg_len >= CMSG_LEN(sizeof(timeval))) {
      timeval t{};
      std::memcpy(&t, CMSG_DATA(c), sizeof t);
      return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + static_cast<std::int64_t>(t.tv_usec) * 1'000;
    }
  }
  return -1;
}

}  // namespace

SocketCanBus::SocketCanBus(UniqueFd fd, std::string name, std::size_t tx_queue_frames)
    : fd_(std::move(fd)), name_(std::move(name)), tx_(tx_queue_frames, name_) {}

Result<std::unique_ptr<SocketCanBus>> SocketCanBus::open(std::string_view interface, SocketCanOptions options) {
  const std::string name(interface);
  if (name.empty() || name.size() >= IFNAMSIZ) {
    return Error::format(Errc::invalid_argument, "SocketCAN: interface name '%s' must be 1..%d characters",
                         name.c_str(), IFNAMSIZ - 1);
  }
  UniqueFd fd(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!fd) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      char text[96];
      return Error::format(Errc::not_supported,
                           "SocketCAN unavailable: the kernel has no AF_CAN support (socket(PF_CAN): %s)",
                           posix::errno_text(err, text, sizeof text));
    }
    return posix::errno_error(err == EPERM || err == EACCES ? Errc::permission : Errc::io, err,
                              "SocketCAN %s: socket(PF_CAN)", name.c_str());
  }
  ifreq request{};
  std::memcpy(request.ifr_name, name.c_str(), name.size() + 1);
  if (::ioctl(fd.get(), SIOCGIFINDEX, &request) != 0) {
    const int err = errno;
    return posix::errno_error(err == ENODEV ? Errc::not_found : Errc::io, err, "SocketCAN %s: no such interface (SIOCGIFINDEX)",
                              name.c_str());
  }
  if (options.receive_own) {
    const int on = 1;
    ::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &on, sizeof on);
  }
  // Without the error frames a bus-off would go unnoticed: a failure here fails open().
  const can_err_mask_t errors = kErrorMask;
  if (::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "SocketCAN %s: CAN_RAW_ERR_FILTER", name.c_str());
  }
  // The kernel's receive time; a kernel that gives neither leaves the frames unstamped (-1).
  const int on = 1;
  if (::setsockopt(fd.get(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) != 0) {
    (void)::setsockopt(fd.get(), SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on);
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "SocketCAN %s: bind", name.c_str());
  }
  return std::unique_ptr<SocketCanBus>(new SocketCanBus(std::move(fd), name, options.tx_queue_frames));
}

Status SocketCanBus::write_frame(const CanFrame& frame) {
  const can_frame out = to_kernel(frame);
  for (;;) {
    const ssize_t n = ::write(fd_.get(), &out, sizeof out);
    if (n == static_cast<ssize_t>(sizeof out)) return {};
    if (n >= 0) return Error::format(Errc::io, "%s: short write of a CAN frame (%zd bytes)", name_.c_str(), n);
    const int err = errno;
    if (err == EINTR) continue;
    // ENOBUFS: the interface's transmit queue is full (the bus is busy or nobody ACKs).
    if (err == EAGAIN || err == EWOULDBLOCK || err == ENOBUFS) {
      return Error::format(Errc::would_block, "%s: transmit queue full", name_.c_str());
    }
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: send", name_.c_str());
  }
}

Status SocketCanBus::write_to(void* self, const CanFrame& frame) {
  return static_cast<SocketCanBus*>(self)->write_frame(frame);
}

Status SocketCanBus::refuse_if_bus_off() {
  if (link_state() != CanLinkState::bus_off) return {};
  const std::size_t dropped = tx_.discard();
  return Error::format(Errc::disconnected, "%s: bus-off, nothing is sent until the controller restarts%s",
                       name_.c_str(), dropped > 0 ? " (queued frames dropped)" : "");
}

Status SocketCanBus::send(const CanFrame& frame) {
  if (Status valid = frame.validate(); !valid) return valid;
  if (Status on_bus = refuse_if_bus_off(); !on_bus) return on_bus;
  return tx_.send(frame, &write_to, this);
}

Status SocketCanBus::flush() {
  if (Status on_bus = refuse_if_bus_off(); !on_bus) return on_bus;
  return tx_.flush(&write_to, this);
}

Result<std::optional<CanFrame>> SocketCanBus::receive() {
  for (;;) {
    can_frame in{};
    iovec data{&in, sizeof in};
    alignas(cmsghdr) std::byte control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(timeval))];
    msghdr message{};
    message.msg_iov = &data;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_.get(), &message, MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(sizeof in)) {
      // Error frames update the link state; they are never data.
      if ((in.can_id & CAN_ERR_FLAG) != 0) {
        error_frames_.fetch_add(1, std::memory_order_relaxed);
        link_state_.store(next_link_state(link_state(), error_from_kernel(in)), std::memory_order_release);
        continue;
      }
      last_receive_unix_ns_ = receive_time(message);
      return std::optional<CanFrame>(from_kernel(in));
    }
    if (n >= 0) return Error::format(Errc::protocol, "%s: short read of a CAN frame (%zd bytes)", name_.c_str(), n);
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::optional<CanFrame>();
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: receive", name_.c_str());
  }
}

Status SocketCanBus::set_filters(std::span<const CanFilter> filters) {
  if (filters.size() > kMaxCanFilters) {
    return Error::format(Errc::capacity, "%s: %zu filters, at most %zu", name_.c_str(), filters.size(), kMaxCanFilters);
  }
  std::array<can_filter, kMaxCanFilters> kernel{};
  for (std::size_t i = 0; i < filters.size(); ++i) {
    const CanFilter& f = filters[i];
    // The EFF flag in the mask makes the kernel compare the id format too.
    kernel[i].can_id = f.id | (f.format == CanFilter::Format::extended ? CAN_EFF_FLAG : 0U);
    kernel[i].can_mask = (f.mask & CAN_EFF_MASK) | (f.format != CanFilter::Format::any ? CAN_EFF_FLAG : 0U);
  }
  const auto bytes = static_cast<socklen_t>(filters.size() * sizeof(can_filter));
  if (::setsockopt(fd_.get(), SOL_CAN_RAW, CAN_RAW_FILTER, filters.empty() ? nullptr : kernel.data(), bytes) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: CAN_RAW_FILTER", name_.c_str());
  }
  return {};
}

}  // namespace sen3bot::hal
