#include "sen3bot/lms200/device.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>

namespace sen3bot::lms200 {

namespace {

constexpr double kRadPerCentiDeg = std::numbers::pi / 18000.0;
// Bytes read from the link per step at most: bounds the work of one step.
constexpr std::size_t kMaxReadPerStep = 4 * TelegramParser::kCapacityBytes;

}  // namespace

Lms200Device::Settings Lms200Device::settings_of(const Lms200Config& c) noexcept {
  Settings s{c.baud, c.variant, c.units, c.measuring_mode, c.lms_address, {}, c.probe_bauds, c.probe_timeout_ms,
             c.reply_timeout_ms, c.config_write_timeout_ms, c.inter_byte_timeout_ms, c.baud_settle_ms,
             c.nak_retry_delay_ms, c.max_tries, c.stale_scan_periods, c.restart_delay_ms, c.stop_to_9600};
  // Shorter passwords are padded with spaces, as the LMS expects 8 bytes.
  for (std::size_t i = 0; i < kPasswordBytes; ++i) s.password[i] = i < c.password.size() ? c.password[i] : ' ';
  return s;
}

static_assert(std::is_trivially_destructible_v<Lms200Device>, "lives in task arenas");

Lms200Device::Lms200Device(const Lms200Config& config, hal::ByteStream& stream, LineControl* line) noexcept
    : config_(settings_of(config)), stream_(&stream), line_(line), parser_(Side::from_device, config.lms_address) {
  // Probe order: the configured rate (a warm restart finds the LMS there), then power-on 9600,
  // then the others.
  auto add = [this](std::uint32_t b) {
    for (std::size_t i = 0; i < probe_count_; ++i)
      if (probe_bauds_[i] == b) return;
    probe_bauds_[probe_count_++] = b;
  };
  add(config_.baud);
  if (config_.probe_bauds && line_ != nullptr)
    for (std::uint32_t b : {9600u, 19200u, 38400u, 500000u}) add(b);
}

LinkState Lms200Device::link_state() const noexcept {
  switch (phase_) {
    case Phase::idle: return LinkState::idle;
    case Phase::probe: return LinkState::probing;
    case Phase::streaming: return LinkState::streaming;
    case Phase::error_wait: return LinkState::error;
    case Phase::stopped: return LinkState::stopped;
    default: return LinkState::configuring;
  }
}

const char* Lms200Device::phase_name() const noexcept {
  switch (phase_) {
    case Phase::idle: return "idle";
    case Phase::probe: return "probe";
    case Phase::set_baud: return "set_baud";
    case Phase::settle: return "settle";
    case Phase::verify_status: return "verify_status";
    case Phase::set_variant: return "set_variant";
    case Phase::read_config: return "read_config";
    case Phase::enter_installation: return "enter_installation";
    case Phase::write_config: return "write_config";
    case Phase::leave_installation: return "leave_installation";
    case Phase::start_stream: return "start_stream";
    case Phase::streaming: return "streaming";
    case Phase::error_wait: return "error_wait";
    case Phase::stop_monitoring: return "stop_monitoring";
    case Phase::stop_baud: return "stop_baud";
    case Phase::stopped: return "stopped";
  }
  return "?";
}

hal::Nanos scan_interval_ns(Variant variant, std::uint32_t baud) noexcept {
  const std::size_t frame = 2u * value_count(variant) + 10u;
  return std::max<hal::Nanos>(scan_period_ns(variant), transmission_ns(frame, baud));
}

hal::Nanos Lms200Device::expected_scan_interval_ns() const noexcept { return scan_interval_ns(config_.variant, baud_); }

hal::Nanos Lms200Device::probe_timeout_ns(std::uint32_t baud) const noexcept {
  // A streaming LMS answers after the telegram it is sending.
  return hal::millis(config_.probe_timeout_ms) + transmission_ns(kMaxFrameBytes, baud);
}

void Lms200Device::start(hal::Nanos now) noexcept {
  stop_requested_ = false;
  probe_index_ = 0;
  enter(now, Phase::probe);
}

void Lms200Device::request_stop(hal::Nanos now) noexcept {
  stop_requested_ = true;
  if (phase_ == Phase::idle || phase_ == Phase::stopped || phase_ == Phase::error_wait) {
    phase_ = Phase::stopped;
    awaiting_ = false;
    return;
  }
  enter(now, Phase::stop_monitoring);
}

bool Lms200Device::switch_host_baud(hal::Nanos now, std::uint32_t baud) noexcept {
  if (line_ != nullptr) {
    if (Status s = line_->set_baud(baud); !s) {
      fail(now, s.error());
      return false;
    }
  }
  baud_ = baud;
  // Whatever arrived at the old rate is noise at the new one.
  parser_.reset();
  return true;
}

void Lms200Device::fail(hal::Nanos now, const Error& error) noexcept {
  last_error_ = error;
  ++error_count_;
  ++counters_.errors;
  awaiting_ = false;
  if (stop_requested_) {
    phase_ = Phase::stopped;
    return;
  }
  phase_ = Phase::error_wait;
  phase_until_ns_ = now + hal::millis(config_.restart_delay_ms);
}

void Lms200Device::send(hal::Nanos now, const Request& request, std::uint8_t reply, hal::Nanos timeout_ns) noexcept {
  pending_ = request;
  expected_reply_ = reply;
  timeout_ns_ = timeout_ns;
  tries_ = 0;
  resend(now);
}

void Lms200Device::resend(hal::Nanos now) noexcept {
  ++tries_;
  pending_written_ = 0;
  awaiting_ = true;
  got_ack_ = false;
  resend_at_ns_ = -1;
  // The timeout counts from the end of our own transmission.
  deadline_ns_ = now + transmission_ns(pending_.size, baud_) + timeout_ns_;
  flush_tx();
}

void Lms200Device::flush_tx() noexcept {
  while (pending_written_ < pending_.size) {
    Result<std::size_t> n = stream_->write(pending_.span().subspan(pending_written_));
    if (!n) {
      fail(last_rx_ns_, n.error());
      return;
    }
    if (*n == 0) return;  // the kernel queue is full; continue next step
    pending_written_ += *n;
  }
}

void Lms200Device::enter(hal::Nanos now, Phase phase) noexcept {
  phase_ = phase;
  awaiting_ = false;
  const hal::Nanos reply = hal::millis(config_.reply_timeout_ms);
  switch (phase) {
    case Phase::probe:
      if (!switch_host_baud(now, probe_bauds_[probe_index_])) return;
      send(now, request_mode(OperatingMode::monitoring), kReplyModeChange, probe_timeout_ns(baud_));
      tries_ = std::max(tries_, config_.max_tries - 1);  // two tries per rate while probing
      break;
    case Phase::set_baud:
      send(now, request_baud(config_.baud), kReplyModeChange, reply);
      break;
    case Phase::settle:
      phase_until_ns_ = now + hal::millis(config_.baud_settle_ms);
      break;
    case Phase::verify_status:
      send(now, request_status(), kReplyStatus, reply);
      break;
    case Phase::set_variant:
      send(now, request_variant(config_.variant), kReplyVariant, reply);
      break;
    case Phase::read_config:
      send(now, request_read_config(), kReplyReadConfig, reply);
      break;
    case Phase::enter_installation:
      send(now, request_installation_mode({config_.password.data(), kPasswordBytes}), kReplyModeChange, reply);
      break;
    case Phase::write_config: {
      ConfigBlock block = config_block_;
      block.bytes[config_offset::kUnits] = static_cast<std::uint8_t>(config_.units);
      block.bytes[config_offset::kMeasuringMode] = static_cast<std::uint8_t>(config_.measuring_mode);
      ++counters_.config_writes;
      send(now, request_write_config(block.span()), kReplyWriteConfig, hal::millis(config_.config_write_timeout_ms));
      break;
    }
    case Phase::leave_installation:
    case Phase::stop_monitoring:
      send(now, request_mode(OperatingMode::monitoring), kReplyModeChange, reply);
      break;
    case Phase::start_stream:
      send(now, request_mode(OperatingMode::continuous_all), kReplyModeChange, reply);
      break;
    case Phase::streaming:
      last_scan_ns_ = now;
      break;
    case Phase::stop_baud:
      send(now, request_baud(9600), kReplyModeChange, reply);
      break;
    case Phase::idle:
    case Phase::error_wait:
    case Phase::stopped:
      break;
  }
}

void Lms200Device::step(hal::Nanos now) noexcept {
  if (phase_ == Phase::idle || phase_ == Phase::stopped) return;
  if (phase_ == Phase::error_wait) {
    if (now < phase_until_ns_) return;
    ++counters_.restarts;
    start(now);
    if (phase_ != Phase::probe) return;
  }

  // Read what the link has, feeding the parser and handling each event as it appears.
  std::array<std::uint8_t, 512> chunk;
  std::size_t total = 0;
  while (total < kMaxReadPerStep) {
    const std::size_t room = std::min(chunk.size(), parser_.free_space());
    if (room == 0) break;
    Result<std::size_t> n = stream_->read({chunk.data(), room});
    if (!n) {
      fail(now, n.error());
      return;
    }
    if (*n == 0) break;
    total += *n;
    last_rx_ns_ = now;
    parser_.push({chunk.data(), *n});
    TelegramParser::Event event;
    while (parser_.next(event)) {
      if (event.kind == TelegramParser::Kind::frame) {
        on_frame(now, event.frame);
      } else if (event.kind == TelegramParser::Kind::ack) {
        if (awaiting_) got_ack_ = true;
      } else if (awaiting_) {
        ++counters_.naks;
        resend_at_ns_ = now + hal::millis(config_.nak_retry_delay_ms);
      }
      if (phase_ == Phase::error_wait || phase_ == Phase::stopped) return;
    }
  }
  // An incomplete telegram with a long silence behind it is not going to complete.
  if (parser_.has_partial() && now - last_rx_ns_ > hal::millis(config_.inter_byte_timeout_ms)) {
    parser_.drop_partial();
    TelegramParser::Event event;
    while (parser_.next(event)) {
      if (event.kind == TelegramParser::Kind::frame) on_frame(now, event.frame);
      if (phase_ == Phase::error_wait || phase_ == Phase::stopped) return;
    }
  }

  if (awaiting_) {
    flush_tx();
    if (phase_ == Phase::error_wait) return;
    if (resend_at_ns_ >= 0 && now >= resend_at_ns_) {
      if (tries_ >= config_.max_tries) {
        fail(now, Error::format(Errc::protocol, "lms200: request 0x%02X refused with NAK %d times",
                                pending_.command(), tries_));
        return;
      }
      resend(now);
    } else if (now >= deadline_ns_) {
      on_timeout(now);
    }
    return;
  }
  if (phase_ == Phase::settle && now >= phase_until_ns_) {
    enter(now, Phase::verify_status);
  } else if (phase_ == Phase::streaming) {
    const hal::Nanos limit = config_.stale_scan_periods * expected_scan_interval_ns() +
                             hal::millis(config_.inter_byte_timeout_ms);
    if (now - last_scan_ns_ > limit) {
      ++counters_.stale_events;
      fail(now, Error::format(Errc::timeout, "lms200: no scan for %.0f ms (stale data)",
                              static_cast<double>(now - last_scan_ns_) / 1e6));
    }
  }
}

void Lms200Device::on_timeout(hal::Nanos now) noexcept {
  ++counters_.timeouts;
  if (tries_ < config_.max_tries) {
    resend(now);
    return;
  }
  awaiting_ = false;
  if (phase_ == Phase::probe) {
    if (++probe_index_ < probe_count_) {
      enter(now, Phase::probe);
    } else {
      fail(now, Error::format(Errc::timeout, "lms200: no reply to 20 25 at any of %zu baud rates on %.*s",
                              probe_count_, static_cast<int>(stream_->name().size()), stream_->name().data()));
    }
    return;
  }
  fail(now, Error::format(Errc::timeout, "lms200: no 0x%02X reply to request 0x%02X in %s after %d tries",
                          expected_reply_, pending_.command(), phase_name(), tries_));
}

void Lms200Device::on_frame(hal::Nanos now, FrameView frame) noexcept {
  if (frame.code() == kReplyScan && phase_ == Phase::streaming) {
    on_scan(now, frame);
    return;
  }
  if (!awaiting_) {
    ++counters_.ignored_frames;
    return;
  }
  if (frame.code() == kReplyRejected) {
    ++counters_.rejected;
    fail(now, Error::format(Errc::protocol, "lms200: request 0x%02X rejected (0x92) in %s", pending_.command(),
                            phase_name()));
    return;
  }
  if (frame.code() != expected_reply_) {
    // Streamed scans still in flight while we stop or probe, for example.
    ++counters_.ignored_frames;
    return;
  }
  if (!got_ack_) ++counters_.missing_acks;
  awaiting_ = false;
  if (frame.len() >= 2) last_status_byte_ = frame.reply_status();
  on_reply(now, frame);
}

void Lms200Device::on_reply(hal::Nanos now, FrameView frame) noexcept {
  switch (phase_) {
    case Phase::probe:
    case Phase::set_baud:
    case Phase::enter_installation:
    case Phase::leave_installation:
    case Phase::start_stream:
    case Phase::stop_monitoring:
    case Phase::stop_baud: {
      Result<ModeChangeReply> r = decode_mode_change(frame);
      if (!r) return fail(now, r.error());
      if (phase_ == Phase::probe) {
        // Any A0 proves the rate; a refusal here would only mean the LMS is busy.
        if (baud_ != config_.baud) return enter(now, Phase::set_baud);
        return enter(now, Phase::verify_status);
      }
      if (r->result != kModeChangeOk) {
        return fail(now, Error::format(Errc::protocol, "lms200: mode change refused in %s (A0 result %u%s)",
                                       phase_name(), r->result,
                                       r->result == kModeChangeBadPassword ? ", wrong password" : ""));
      }
      switch (phase_) {
        case Phase::set_baud:
          // The reply came at the old rate; the LMS is now at the new one.
          if (!switch_host_baud(now, config_.baud)) return;
          return enter(now, Phase::settle);
        case Phase::enter_installation: return enter(now, Phase::write_config);
        case Phase::leave_installation: return enter(now, Phase::start_stream);
        case Phase::start_stream: return enter(now, Phase::streaming);
        case Phase::stop_monitoring:
          // Without control of the host's rate (a fixed-rate bridge) the scanner must stay
          // where the next session will look for it.
          if (config_.stop_to_9600 && baud_ != 9600 && line_ != nullptr) return enter(now, Phase::stop_baud);
          phase_ = Phase::stopped;
          return;
        case Phase::stop_baud:
          switch_host_baud(now, 9600);
          phase_ = Phase::stopped;
          return;
        default: return;
      }
    }
    case Phase::verify_status: {
      Result<StatusReply> r = decode_status(frame);
      if (!r) return fail(now, r.error());
      status_ = *r;
      if (r->device_status != kDeviceStatusOk) ++counters_.fault_reports;
      if (r->baud != 0 && r->baud != baud_) {
        return fail(now, Error::format(Errc::protocol, "lms200: status reports %u baud, host is at %u", r->baud,
                                       baud_));
      }
      if (!(r->variant == config_.variant)) return enter(now, Phase::set_variant);
      return enter(now, Phase::read_config);
    }
    case Phase::set_variant: {
      Result<VariantReply> r = decode_variant(frame);
      if (!r) return fail(now, r.error());
      if (!r->accepted) {
        return fail(now, Error::format(Errc::config, "lms200: variant %u/%u refused", config_.variant.angle_deg,
                                       config_.variant.resolution_cdeg));
      }
      return enter(now, Phase::read_config);
    }
    case Phase::read_config: {
      Result<ConfigReply> r = decode_read_config(frame);
      if (!r) return fail(now, r.error());
      config_block_ = r->block;
      const bool same = r->block.units() == static_cast<std::uint8_t>(config_.units) &&
                        r->block.measuring_mode() == static_cast<std::uint8_t>(config_.measuring_mode);
      return enter(now, same ? Phase::start_stream : Phase::enter_installation);
    }
    case Phase::write_config: {
      Result<ConfigReply> r = decode_write_config(frame);
      if (!r) return fail(now, r.error());
      if (!r->accepted) return fail(now, Error(Errc::config, "lms200: configuration write refused (F7 00)"));
      config_block_.bytes[config_offset::kUnits] = static_cast<std::uint8_t>(config_.units);
      config_block_.bytes[config_offset::kMeasuringMode] = static_cast<std::uint8_t>(config_.measuring_mode);
      return enter(now, Phase::leave_installation);
    }
    default: ++counters_.ignored_frames; return;
  }
}

bool Lms200Device::scanner_fault() const noexcept {
  const StatusLevel level = status_level(last_status_byte_);
  return status_.device_status != kDeviceStatusOk || level == StatusLevel::error || level == StatusLevel::fatal;
}

bool Lms200Device::take_new_scan(LaserScan& out) noexcept {
  if (scan_.sequence == taken_sequence_) return false;
  out = scan_;
  taken_sequence_ = scan_.sequence;
  return true;
}

void Lms200Device::on_scan(hal::Nanos now, FrameView frame) noexcept {
  Result<ScanTelegram> decoded = decode_scan(frame);
  if (!decoded) {
    ++counters_.bad_scans;
    return;
  }
  const ScanTelegram& t = *decoded;
  last_status_byte_ = t.status;
  if (t.count != value_count(config_.variant) || t.partial) {
    ++counters_.bad_scans;
    return;
  }
  const auto mode = static_cast<MeasuringMode>(config_block_.measuring_mode());
  const ValueLayout layout = value_layout(mode);
  const double unit_m = metres_per_unit(t.units);
  scan_.received_ns = now;
  scan_.stamp_ns = now - transmission_ns(frame.bytes.size(), baud_);
  scan_.sequence += 1;
  scan_.angle_min_rad = static_cast<float>(-config_.variant.angle_deg * 50.0 * kRadPerCentiDeg);
  scan_.angle_increment_rad = static_cast<float>(config_.variant.resolution_cdeg * kRadPerCentiDeg);
  scan_.scan_period_s = static_cast<float>(hal::to_seconds(scan_period_ns(config_.variant)));
  scan_.range_max_m = static_cast<float>((layout.first_code - 1) * unit_m);
  scan_.count = t.count;
  scan_.units = static_cast<std::uint8_t>(t.units);
  scan_.measuring_mode = static_cast<std::uint8_t>(mode);
  scan_.status = t.status;
  scan_.link_state = LinkState::streaming;
  scan_.device_status = status_.device_status;
  scan_.scanner_fault = scanner_fault();
  scan_.baud = baud_;
  const ParserStats& ps = parser_.stats();
  scan_.crc_errors = static_cast<std::uint32_t>(ps.crc_errors);
  scan_.dropped_bytes = static_cast<std::uint32_t>(ps.garbage_bytes + ps.dropped_partials);
  scan_.restarts = static_cast<std::uint32_t>(counters_.restarts);
  scan_.stale_events = static_cast<std::uint32_t>(counters_.stale_events);
  for (std::size_t i = 0; i < t.count; ++i) {
    const ScanValue v = decode_value(t.words[i], mode);
    scan_.flags[i] = v.flags;
    scan_.invalid_reason[i] = static_cast<std::uint8_t>(v.reason);
    scan_.ranges_m[i] = v.reason == InvalidReason::none ? static_cast<float>(v.distance * unit_m)
                                                        : std::numeric_limits<float>::quiet_NaN();
  }
  ++counters_.scans;
  last_scan_ns_ = now;
}

}  // namespace sen3bot::lms200
