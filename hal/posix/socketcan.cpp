// SocketCAN raw sockets (Linux). Absent AF_CAN support is an expected, reported condition.
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

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

}  // namespace

SocketCanBus::SocketCanBus(UniqueFd fd, std::string name) : fd_(std::move(fd)), name_(std::move(name)) {}

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
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "SocketCAN %s: bind", name.c_str());
  }
  return std::unique_ptr<SocketCanBus>(new SocketCanBus(std::move(fd), name));
}

Status SocketCanBus::send(const CanFrame& frame) {
  if (Status valid = frame.validate(); !valid) return valid;
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

Result<std::optional<CanFrame>> SocketCanBus::receive() {
  for (;;) {
    can_frame in{};
    const ssize_t n = ::read(fd_.get(), &in, sizeof in);
    if (n == static_cast<ssize_t>(sizeof in)) {
      // Error frames arrive only if an error mask was set; never hand them out as data.
      if ((in.can_id & CAN_ERR_FLAG) != 0) continue;
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
