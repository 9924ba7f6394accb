#include "loopback_session.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <ctime>
#include <string>
#include <thread>

#include "sen3bot/capture/writer.hpp"

namespace sen3bot::capture::test {

namespace {

// --- P2OS (Pioneer 2 operating system manual, "Client-server communication packet") ---
constexpr std::uint8_t kP2osHeader0 = 0xFA;
constexpr std::uint8_t kP2osHeader1 = 0xFB;
constexpr std::uint8_t kP2osSync0 = 0;
constexpr std::uint8_t kP2osSync1 = 1;
constexpr std::uint8_t kP2osSync2 = 2;
constexpr std::uint8_t kP2osOpen = 1;
constexpr std::uint8_t kP2osClose = 2;
constexpr std::uint8_t kP2osEnable = 4;
constexpr std::uint8_t kP2osVel = 11;
constexpr std::uint8_t kP2osStop = 29;
constexpr std::uint8_t kP2osArgInt = 0x3B;        // argument type: positive integer
constexpr std::uint8_t kP2osSipStopped = 0x32;    // server information packet, motors stopped
constexpr std::uint8_t kP2osSipMoving = 0x33;     // ... motors moving
constexpr hal::Nanos kP2osSipPeriod_ns = hal::millis(10);  // real base: 100 ms; shortened
constexpr hal::Nanos kP2osReplyDelay_ns = hal::millis(2);

// --- SICK LMS200 (LMS2xx telegram listing: STX, address, length, command, data, CRC) ---
constexpr std::uint8_t kLmsStx = 0x02;
constexpr std::uint8_t kLmsHostAddress = 0x00;    // telegrams to the scanner
constexpr std::uint8_t kLmsReplyAddress = 0x80;   // telegrams from the scanner
constexpr std::uint8_t kLmsAck = 0x06;
constexpr std::uint8_t kLmsModeCommand = 0x20;
constexpr std::uint8_t kLmsModeBaud38400 = 0x40;
constexpr std::uint8_t kLmsModeContinuous = 0x24;
constexpr std::uint8_t kLmsModeStop = 0x25;
constexpr std::uint8_t kLmsModeReply = 0xA0;
constexpr std::uint8_t kLmsScanReply = 0xB0;
constexpr std::uint8_t kLmsStatusOk = 0x10;
constexpr std::uint16_t kLmsCrcPolynomial = 0x8005;
constexpr std::size_t kLmsScanValues = 181;        // 180 degrees at 1 degree resolution
constexpr hal::Nanos kLmsScanPeriod_ns = hal::millis(15);
constexpr hal::Nanos kLmsReplyDelay_ns = hal::millis(3);

constexpr int kP2osSipCount = 6;   // SIPs after ENABLE, again after VEL
constexpr int kLmsScanCount = 8;

void put_le16(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v));
  b.push_back(static_cast<std::uint8_t>(v >> 8));
}

Bytes sip(int index, bool moving) {
  // type, x, y, theta, left and right velocity, battery (decivolts), stall/bump, control,
  // flags, compass, sonar count: the fields of a P2OS standard SIP, values made up.
  Bytes p{moving ? kP2osSipMoving : kP2osSipStopped};
  const auto x = static_cast<std::uint16_t>(moving ? 100 + 20 * index : 100);
  put_le16(p, x);
  put_le16(p, 250);
  put_le16(p, static_cast<std::uint16_t>(index * 3));
  put_le16(p, moving ? 200 : 0);
  put_le16(p, moving ? 200 : 0);
  p.push_back(120);
  put_le16(p, 0);
  put_le16(p, 0);
  put_le16(p, static_cast<std::uint16_t>(0x0101 + index));
  p.push_back(0);
  p.push_back(0);
  return p2os_packet(p);
}

Bytes lms_mode_reply() {
  const std::uint8_t reply[] = {kLmsModeReply, 0x00, kLmsStatusOk};
  return lms200_telegram(kLmsReplyAddress, reply);
}

Bytes lms_scan(int index) {
  Bytes data{kLmsScanReply};
  put_le16(data, static_cast<std::uint16_t>(kLmsScanValues));
  for (std::size_t i = 0; i < kLmsScanValues; ++i) {
    // A wall 2 m away with a box in the middle, drifting by scan: covers many byte values.
    const std::size_t distance_mm = (i > 80 && i < 100 ? 900 : 2000) + static_cast<std::size_t>(index) * 7 + i;
    put_le16(data, static_cast<std::uint16_t>(distance_mm));
  }
  data.push_back(kLmsStatusOk);
  return lms200_telegram(kLmsReplyAddress, data);
}

Bytes lms_request(std::uint8_t mode) {
  const std::uint8_t command[] = {kLmsModeCommand, mode};
  return lms200_telegram(kLmsHostAddress, command);
}

std::size_t reply_bytes(const Exchange& e) {
  std::size_t n = 0;
  for (const Reply& r : e.replies) n += r.bytes.size();
  return n;
}

// ---------- pseudo-terminals (posix_openpt directly; independent of hal's PtyPair) ----------

struct Pty {
  int master_fd = -1;
  int slave_fd = -1;
  std::string slave_name;
};

void close_pty(Pty& pty) {
  if (pty.slave_fd >= 0) ::close(pty.slave_fd);
  if (pty.master_fd >= 0) ::close(pty.master_fd);
  pty.slave_fd = pty.master_fd = -1;
}

Result<Pty> open_pty() {
  Pty pty;
  pty.master_fd = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (pty.master_fd < 0) return Error::from_errno(Errc::not_supported, "posix_openpt", errno);
  char name[128];
  if (::grantpt(pty.master_fd) != 0 || ::unlockpt(pty.master_fd) != 0 ||
      ::ptsname_r(pty.master_fd, name, sizeof name) != 0) {
    const int err = errno;
    close_pty(pty);
    return Error::from_errno(Errc::io, "pty setup", err);
  }
  pty.slave_name = name;
  pty.slave_fd = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
  if (pty.slave_fd < 0) {
    const int err = errno;
    close_pty(pty);
    return Error::from_errno(Errc::io, "open pty slave", err);
  }
  // Raw: no echo, no CR/LF translation, no signals; every byte passes unchanged.
  termios tio{};
  if (::tcgetattr(pty.slave_fd, &tio) != 0) {
    const int err = errno;
    close_pty(pty);
    return Error::from_errno(Errc::io, "tcgetattr", err);
  }
  ::cfmakeraw(&tio);
  if (::tcsetattr(pty.slave_fd, TCSANOW, &tio) != 0) {
    const int err = errno;
    close_pty(pty);
    return Error::from_errno(Errc::io, "tcsetattr", err);
  }
  return pty;
}

// The firmware end of a pty as a non-blocking ByteStream.
class FdStream final : public hal::ByteStream {
 public:
  FdStream(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override {
    const ssize_t n = ::read(fd_, out.data(), out.size());
    if (n > 0) return static_cast<std::size_t>(n);
    if (n == 0) return Error(Errc::disconnected, "pty closed");
    if (errno == EAGAIN || errno == EINTR) return std::size_t{0};
    if (errno == EIO) return Error(Errc::disconnected, "pty hung up");
    return Error::from_errno(Errc::io, "pty read", errno);
  }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override {
    const ssize_t n = ::write(fd_, data.data(), data.size());
    if (n >= 0) return static_cast<std::size_t>(n);
    if (errno == EAGAIN || errno == EINTR) return std::size_t{0};
    return Error::from_errno(errno == EIO ? Errc::disconnected : Errc::io, "pty write", errno);
  }
  [[nodiscard]] int poll_fd() const override { return fd_; }
  [[nodiscard]] std::string_view name() const override { return name_; }

 private:
  int fd_;
  std::string name_;
};

constexpr int kDeviceTimeout_ms = 5000;

// Device emulator at the master end: wait for each request, check it, send the replies.
void run_device(int fd, const Script& script, std::string& failure) {
  for (const Exchange& e : script) {
    Bytes got;
    while (got.size() < e.request.size()) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, kDeviceTimeout_ms) <= 0) {
        failure = "device: timed out waiting for a request";
        return;
      }
      std::uint8_t buf[256];
      const std::size_t want = std::min(sizeof buf, e.request.size() - got.size());
      const ssize_t n = ::read(fd, buf, want);
      if (n <= 0) {
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        failure = "device: read failed";
        return;
      }
      got.insert(got.end(), buf, buf + n);
    }
    if (got != e.request) {
      failure = "device: unexpected request";
      return;
    }
    for (const Reply& r : e.replies) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(r.delay_ns));
      std::size_t done = 0;
      while (done < r.bytes.size()) {
        const ssize_t n = ::write(fd, r.bytes.data() + done, r.bytes.size() - done);
        if (n < 0) {
          if (errno == EAGAIN || errno == EINTR) continue;
          failure = "device: write failed";
          return;
        }
        done += static_cast<std::size_t>(n);
      }
    }
  }
}

std::int64_t wall_now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * hal::kNanosPerSecond + ts.tv_nsec;
}

}  // namespace

Bytes p2os_packet(std::span<const std::uint8_t> payload) {
  // Checksum: sum of big-endian 16-bit words of the payload, an odd last byte XORed in;
  // sent high byte first (P2OS manual, "Packet checksum").
  std::uint32_t sum = 0;
  std::size_t i = 0;
  for (; i + 1 < payload.size(); i += 2) sum = (sum + static_cast<std::uint32_t>((payload[i] << 8) | payload[i + 1])) & 0xFFFF;
  if (i < payload.size()) sum ^= payload[i];
  Bytes b{kP2osHeader0, kP2osHeader1, static_cast<std::uint8_t>(payload.size() + 2)};
  b.insert(b.end(), payload.begin(), payload.end());
  b.push_back(static_cast<std::uint8_t>(sum >> 8));
  b.push_back(static_cast<std::uint8_t>(sum));
  return b;
}

std::uint16_t lms200_crc16(std::span<const std::uint8_t> bytes) {
  // The LMS2xx CRC: a shift register over the current and previous byte (telegram listing).
  std::uint16_t crc = 0;
  std::uint8_t previous = 0;
  for (const std::uint8_t current : bytes) {
    if (crc & 0x8000) {
      crc = static_cast<std::uint16_t>(((crc & 0x7FFF) << 1) ^ kLmsCrcPolynomial);
    } else {
      crc = static_cast<std::uint16_t>(crc << 1);
    }
    crc = static_cast<std::uint16_t>(crc ^ (current | (previous << 8)));
    previous = current;
  }
  return crc;
}

Bytes lms200_telegram(std::uint8_t address, std::span<const std::uint8_t> command_and_data) {
  Bytes b{kLmsStx, address};
  put_le16(b, static_cast<std::uint16_t>(command_and_data.size()));
  b.insert(b.end(), command_and_data.begin(), command_and_data.end());
  put_le16(b, lms200_crc16(b));
  return b;
}

Script p2os_script() {
  auto command = [](std::initializer_list<std::uint8_t> payload) {
    return p2os_packet(std::span<const std::uint8_t>(payload.begin(), payload.size()));
  };
  const Bytes sync0 = command({kP2osSync0});
  const Bytes sync1 = command({kP2osSync1});
  // SYNC2 reply: the robot's name, class and subclass, each NUL-terminated.
  Bytes sync2_reply_payload{kP2osSync2};
  for (const char* s : {"sen3bot-loopback", "Pioneer", "p2dx"}) {
    for (const char* c = s; *c != '\0'; ++c) sync2_reply_payload.push_back(static_cast<std::uint8_t>(*c));
    sync2_reply_payload.push_back(0);
  }
  Script script;
  script.push_back({sync0, {{kP2osReplyDelay_ns, sync0}}, std::nullopt});
  script.push_back({sync1, {{kP2osReplyDelay_ns, sync1}}, std::nullopt});
  script.push_back({command({kP2osSync2}), {{kP2osReplyDelay_ns, p2os_packet(sync2_reply_payload)}}, std::nullopt});
  script.push_back({command({kP2osOpen}), {}, std::nullopt});
  Exchange enable{command({kP2osEnable, kP2osArgInt, 0x01, 0x00}), {}, std::nullopt};
  for (int i = 0; i < kP2osSipCount; ++i) enable.replies.push_back({kP2osSipPeriod_ns, sip(i, false)});
  script.push_back(enable);
  Exchange vel{command({kP2osVel, kP2osArgInt, 0xC8, 0x00}), {}, std::nullopt};  // 200 mm/s
  for (int i = 0; i < kP2osSipCount; ++i) vel.replies.push_back({kP2osSipPeriod_ns, sip(kP2osSipCount + i, true)});
  script.push_back(vel);
  script.push_back({command({kP2osStop}), {{kP2osSipPeriod_ns, sip(2 * kP2osSipCount, false)}}, std::nullopt});
  script.push_back({command({kP2osClose}), {}, std::nullopt});
  return script;
}

Script lms200_script() {
  Script script;
  script.push_back({lms_request(kLmsModeBaud38400),
                    {{kLmsReplyDelay_ns, Bytes{kLmsAck}}, {kLmsReplyDelay_ns, lms_mode_reply()}},
                    kLmsFastBaud});
  Exchange start{lms_request(kLmsModeContinuous),
                 {{kLmsReplyDelay_ns, Bytes{kLmsAck}}, {kLmsReplyDelay_ns, lms_mode_reply()}},
                 std::nullopt};
  for (int i = 0; i < kLmsScanCount; ++i) start.replies.push_back({kLmsScanPeriod_ns, lms_scan(i)});
  script.push_back(start);
  script.push_back({lms_request(kLmsModeStop),
                    {{kLmsReplyDelay_ns, Bytes{kLmsAck}}, {kLmsReplyDelay_ns, lms_mode_reply()}},
                    std::nullopt});
  return script;
}

Bytes script_tx(const Script& script) {
  Bytes out;
  for (const Exchange& e : script) out.insert(out.end(), e.request.begin(), e.request.end());
  return out;
}

Bytes script_rx(const Script& script) {
  Bytes out;
  for (const Exchange& e : script)
    for (const Reply& r : e.replies) out.insert(out.end(), r.bytes.begin(), r.bytes.end());
  return out;
}

CaptureInfo session_info(std::int64_t start_wall_ns, hal::Nanos start_monotonic_ns) {
  CaptureInfo info;
  info.start_wall_ns = start_wall_ns;
  info.start_monotonic_ns = start_monotonic_ns;
  info.channels = {ChannelDecl{kP2osChannel, "p2os", kStartBaud}, ChannelDecl{kLms200Channel, "lms200", kStartBaud}};
  return info;
}

Status run_firmware_side(std::span<FirmwareChannel> channels, const std::function<bool()>& wait) {
  struct Progress {
    std::size_t exchange = 0;
    std::size_t sent = 0;
    std::size_t received = 0;   // in the current exchange
    std::size_t rx_offset = 0;  // in the channel's whole rx stream
    Bytes expected_rx;
  };
  std::vector<Progress> progress(channels.size());
  for (std::size_t i = 0; i < channels.size(); ++i) progress[i].expected_rx = script_rx(channels[i].script);
  std::uint8_t buf[kFirmwareReadBytes];

  for (;;) {
    bool all_done = true;
    bool moved = false;
    for (std::size_t i = 0; i < channels.size(); ++i) {
      FirmwareChannel& ch = channels[i];
      Progress& p = progress[i];
      if (p.exchange >= ch.script.size()) continue;
      all_done = false;
      const Exchange& e = ch.script[p.exchange];
      if (p.sent < e.request.size()) {
        auto n = ch.stream.write(std::span<const std::uint8_t>(e.request).subspan(p.sent));
        if (!n) return n.error();
        p.sent += *n;
        moved = moved || *n > 0;
        continue;
      }
      if (p.received < reply_bytes(e)) {
        auto n = ch.stream.read(buf);
        if (!n) return n.error();
        for (std::size_t k = 0; k < *n; ++k, ++p.rx_offset) {
          if (p.rx_offset >= p.expected_rx.size() || buf[k] != p.expected_rx[p.rx_offset])
            return Error::format(Errc::protocol, "%.*s: unexpected byte 0x%02x at rx offset %zu",
                                 static_cast<int>(ch.stream.name().size()), ch.stream.name().data(), buf[k],
                                 p.rx_offset);
        }
        p.received += *n;
        moved = moved || *n > 0;
      }
      if (p.received >= reply_bytes(e)) {
        if (e.baud_after && ch.recorder != nullptr) ch.recorder->note_baud_change(*e.baud_after);
        ++p.exchange;
        p.sent = p.received = 0;
        moved = true;
      }
    }
    if (all_done) return {};
    if (!moved && !wait()) return Error(Errc::timeout, "session stalled");
  }
}

Status record_loopback_session(const std::filesystem::path& path) {
  auto p2os_pty = open_pty();
  if (!p2os_pty) return p2os_pty.error();
  auto lms_pty = open_pty();
  if (!lms_pty) {
    close_pty(*p2os_pty);
    return lms_pty.error();
  }

  hal::PosixClock clock;
  CaptureWriter writer(1 << 20);
  Status status = writer.open(path, session_info(wall_now_ns(), clock.now()));
  if (status) {
    FdStream p2os_fd(p2os_pty->slave_fd, p2os_pty->slave_name);
    FdStream lms_fd(lms_pty->slave_fd, lms_pty->slave_name);
    RecordingStream p2os(p2os_fd, writer, kP2osChannel, clock);
    RecordingStream lms(lms_fd, writer, kLms200Channel, clock);
    const Script p2os_steps = p2os_script();
    const Script lms_steps = lms200_script();

    std::atomic<bool> stop_flushing{false};
    std::thread flusher([&] {
      while (!stop_flushing.load()) {
        (void)writer.flush();
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
    std::string p2os_failure, lms_failure;
    std::thread p2os_device(run_device, p2os_pty->master_fd, std::cref(p2os_steps), std::ref(p2os_failure));
    std::thread lms_device(run_device, lms_pty->master_fd, std::cref(lms_steps), std::ref(lms_failure));

    FirmwareChannel channels[] = {{p2os, p2os_steps, &p2os}, {lms, lms_steps, &lms}};
    const hal::Nanos deadline_ns = clock.now() + hal::seconds(10);
    status = run_firmware_side(channels, [&] {
      pollfd fds[] = {{p2os.poll_fd(), POLLIN, 0}, {lms.poll_fd(), POLLIN, 0}};
      (void)::poll(fds, 2, 1);
      return clock.now() < deadline_ns;
    });
    p2os_device.join();
    lms_device.join();
    stop_flushing.store(true);
    flusher.join();
    if (status && !p2os_failure.empty()) status = Error(Errc::protocol, p2os_failure);
    if (status && !lms_failure.empty()) status = Error(Errc::protocol, lms_failure);
    Status closed = writer.close();
    if (status) status = closed;
    if (status && writer.dropped_records() != 0) status = Error(Errc::capacity, "capture dropped records");
  }
  close_pty(*p2os_pty);
  close_pty(*lms_pty);
  return status;
}

Status write_synthetic_session(const std::filesystem::path& path) {
  struct Event {
    hal::Nanos t_ns;
    std::uint8_t channel;
    RecordKind kind;
    Bytes bytes;
    std::uint32_t baud;
  };
  constexpr std::size_t kReadPieceBytes = 64;  // how a 64-byte UART FIFO would hand data over
  constexpr hal::Nanos kThink_ns = hal::micros(500);
  constexpr hal::Nanos kBitsPerByte = 10;  // 8N1: start + 8 data + stop
  std::vector<Event> events;
  auto add_channel = [&](std::uint8_t channel, const Script& script, hal::Nanos t_ns) {
    std::uint32_t baud = kStartBaud;
    auto transfer_ns = [&](std::size_t bytes) {
      return static_cast<hal::Nanos>(bytes) * kBitsPerByte * hal::kNanosPerSecond / baud;
    };
    for (const Exchange& e : script) {
      events.push_back({t_ns, channel, RecordKind::tx, e.request, 0});
      t_ns += transfer_ns(e.request.size());
      for (const Reply& r : e.replies) {
        t_ns += r.delay_ns;
        for (std::size_t at = 0; at < r.bytes.size(); at += kReadPieceBytes) {
          const std::size_t n = std::min(kReadPieceBytes, r.bytes.size() - at);
          t_ns += transfer_ns(n);
          events.push_back({t_ns, channel, RecordKind::rx,
                            Bytes(r.bytes.begin() + static_cast<long>(at), r.bytes.begin() + static_cast<long>(at + n)), 0});
        }
      }
      if (e.baud_after) {
        baud = *e.baud_after;
        events.push_back({t_ns, channel, RecordKind::baud_change, {}, baud});
      }
      t_ns += kThink_ns;
    }
  };
  add_channel(kP2osChannel, p2os_script(), 0);
  add_channel(kLms200Channel, lms200_script(), hal::millis(1));  // starts a little later
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t_ns < b.t_ns; });

  const CaptureInfo info = two_channel_info();
  CaptureWriter writer(1 << 20);
  if (Status s = writer.open(path, session_info(info.start_wall_ns, info.start_monotonic_ns)); !s) return s;
  for (const Event& e : events) {
    const hal::Nanos now_ns = info.start_monotonic_ns + e.t_ns;
    const bool ok = e.kind == RecordKind::baud_change
                        ? writer.record_baud_change(now_ns, e.channel, e.baud)
                        : writer.record(now_ns, e.channel, e.kind == RecordKind::rx ? Direction::rx : Direction::tx,
                                        e.bytes);
    if (!ok) return Error(Errc::capacity, "synthetic session: record dropped");
  }
  return writer.close();
}

}  // namespace sen3bot::capture::test
