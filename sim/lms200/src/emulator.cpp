#include "sen3bot/sim/lms200/emulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string_view>

namespace sen3bot::lms200 {

namespace {

constexpr double kRadPerCentiDeg = std::numbers::pi / 18000.0;
// The type string public drivers check for ("LMS200;30106" prefix, 21 characters).
constexpr std::string_view kTypeString = "LMS200;301063;V02.10 ";
constexpr std::string_view kSoftwareVersion = "V02.10 ";
constexpr std::string_view kBootVersion = "V01.00 ";
// Status block offsets beyond those the driver decodes.
constexpr std::size_t kStatusLaserOn = 123;
constexpr std::size_t kStatusBootVersion = 124;

void put_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}

}  // namespace

// --- WallWorld ---------------------------------------------------------------------------------

bool WallWorld::add_segment(Segment s) noexcept {
  if (count_ == kMaxSegments) return false;
  segments_[count_++] = s;
  return true;
}

bool WallWorld::add_rectangle(double min_x_m, double min_y_m, double max_x_m, double max_y_m) noexcept {
  return add_segment({min_x_m, min_y_m, max_x_m, min_y_m}) && add_segment({max_x_m, min_y_m, max_x_m, max_y_m}) &&
         add_segment({max_x_m, max_y_m, min_x_m, max_y_m}) && add_segment({min_x_m, max_y_m, min_x_m, min_y_m});
}

WallWorld WallWorld::room_with_box(double width_m, double depth_m, double box_x_m, double box_y_m, double box_m) {
  WallWorld w;
  w.add_rectangle(0, 0, width_m, depth_m);
  const double h = box_m / 2;
  w.add_rectangle(box_x_m - h, box_y_m - h, box_x_m + h, box_y_m + h);
  w.set_sensor_pose(width_m / 2, depth_m / 2, 0);
  return w;
}

double WallWorld::cast(double x_m, double y_m, double angle_rad) const noexcept {
  const double dx = std::cos(angle_rad);
  const double dy = std::sin(angle_rad);
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < count_; ++i) {
    const Segment& s = segments_[i];
    const double ex = s.x1_m - s.x0_m;
    const double ey = s.y1_m - s.y0_m;
    // Solve origin + t*d = p0 + u*e for t >= 0, u in [0, 1].
    const double denom = dx * ey - dy * ex;
    if (std::abs(denom) < 1e-12) continue;
    const double wx = s.x0_m - x_m;
    const double wy = s.y0_m - y_m;
    const double t = (wx * ey - wy * ex) / denom;
    const double u = (wx * dy - wy * dx) / denom;
    if (t >= 0 && u >= -1e-12 && u <= 1 + 1e-12 && t < best) best = t;
  }
  return best;
}

void WallWorld::ranges(hal::Nanos, const ScanGeometry& geometry, std::span<float> out_m) {
  const SensorPose pose = sensor_pose();
  const std::size_t n = std::min(geometry.count, out_m.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double a = pose.theta_rad + geometry.angle_min_rad + static_cast<double>(i) * geometry.angle_increment_rad;
    out_m[i] = static_cast<float>(cast(pose.x_m, pose.y_m, a));
  }
}

// --- Lms200Emulator ----------------------------------------------------------------------------

Lms200Emulator::Lms200Emulator(const EmulatorOptions& options, hal::ByteStream& stream, RangeSource& world,
                               ClientLine* client) noexcept
    : options_(options),
      stream_(stream),
      world_(world),
      client_(client),
      parser_(Side::from_host),
      baud_(options.initial_baud),
      variant_(options.variant) {
  power_cycle(0);
}

void Lms200Emulator::power_cycle(hal::Nanos now) noexcept {
  baud_ = options_.initial_baud;
  pending_baud_ = 0;
  mode_ = OperatingMode::monitoring;
  installation_ = false;
  variant_ = options_.variant;
  config_.fill(0);
  config_[config_offset::kBlanking] = 0;
  config_[2] = 0x46;  // stop threshold, a typical factory value
  config_[config_offset::kAvailability] = options_.availability;
  config_[config_offset::kMeasuringMode] = static_cast<std::uint8_t>(options_.measuring_mode);
  config_[config_offset::kUnits] = static_cast<std::uint8_t>(options_.units);
  config_reply_at_ns_ = -1;
  q_head_ = q_tail_ = 0;
  line_free_ns_ = now;
  parser_.reset();
}

ScanGeometry Lms200Emulator::geometry() const noexcept {
  ScanGeometry g;
  g.count = value_count(variant_);
  g.angle_increment_rad = variant_.resolution_cdeg * kRadPerCentiDeg;
  g.angle_min_rad = -variant_.angle_deg * 50.0 * kRadPerCentiDeg;
  const ValueLayout layout = value_layout(measuring_mode());
  g.range_max_m = (layout.first_code - 1) * metres_per_unit(units());
  return g;
}

std::size_t Lms200Emulator::scan_words(hal::Nanos t, std::span<std::uint16_t> out) noexcept {
  return fill_words(t, out, mode_ == OperatingMode::partial_scans);
}

std::size_t Lms200Emulator::fill_words(hal::Nanos t, std::span<std::uint16_t> out, bool partial_raster) noexcept {
  ScanGeometry g = geometry();
  if (partial_raster && variant_.resolution_cdeg != 100) {
    // One mirror revolution: the 1 deg raster shifted by the current offset.
    g.count = variant_.angle_deg + 1u;
    g.angle_min_rad += partial_offset_ * 25 * kRadPerCentiDeg;
    g.angle_increment_rad = 100 * kRadPerCentiDeg;
  }
  const std::size_t n = std::min(g.count, out.size());
  world_.ranges(t, g, {ranges_m_.data(), n});
  const MeasuringMode mode = measuring_mode();
  const ValueLayout layout = value_layout(mode);
  const double per_unit = metres_per_unit(units());
  for (std::size_t i = 0; i < n; ++i) {
    const float r = ranges_m_[i];
    std::uint16_t d;
    if (!std::isfinite(r) || r > g.range_max_m) {
      d = code_value(InvalidReason::over_maximum, layout);
    } else {
      const long v = std::lround(std::max(0.0f, r) / per_unit);
      d = v >= layout.first_code ? code_value(InvalidReason::over_maximum, layout) : static_cast<std::uint16_t>(v);
    }
    out[i] = encode_value(d, 0, mode);
  }
  return n;
}

bool Lms200Emulator::enqueue(std::span<const std::uint8_t> bytes) noexcept {
  if (kQueueBytes - queued() < bytes.size()) return false;
  // An idle line starts sending now, not when it last went idle.
  if (queued() == 0) line_free_ns_ = std::max(line_free_ns_, now_);
  for (std::uint8_t b : bytes) queue_[q_tail_++ % kQueueBytes] = b;
  return true;
}

std::uint8_t Lms200Emulator::status_byte() const noexcept {
  const std::uint8_t s = options_.status;
  if (!options_.faults.device_fault) return s;
  const StatusLevel level = status_level(s);
  return level == StatusLevel::fatal ? s : with_status_level(s, StatusLevel::error);
}

std::uint8_t Lms200Emulator::device_status() const noexcept {
  const StatusLevel level = status_level(status_byte());
  return level == StatusLevel::error || level == StatusLevel::fatal ? kDeviceStatusFault : kDeviceStatusOk;
}

void Lms200Emulator::reply(std::uint8_t code, std::span<const std::uint8_t> data, bool ack) noexcept {
  if (ack && !options_.faults.suppress_ack) {
    const std::uint8_t a = kAck;
    enqueue({&a, 1});
  }
  const std::size_t n = make_reply(code, data, status_byte(), frame_, options_.address);
  enqueue({frame_.data(), n});
}

hal::Nanos Lms200Emulator::stream_period_ns() const noexcept {
  return mode_ == OperatingMode::partial_scans ? kMirrorPeriodNs : scan_period_ns(variant_);
}

void Lms200Emulator::start_stream(hal::Nanos now, OperatingMode mode) noexcept {
  mode_ = mode;
  installation_ = false;
  partial_offset_ = 0;
  // The first streamed scan is the next one the mirror completes, counted in the new mode's
  // period: partial scans count mirror turns, the others complete scans.
  last_scan_sent_ = now / stream_period_ns() - 1;
  if (mode == OperatingMode::mean_values) {
    // Means are numbered from 1; the first needs mean_samples_ scans from now.
    last_scan_sent_ = 0;
    mean_blocks_ = 0;
    last_scan_taken_ = now / scan_period_ns(variant_) - 1;
    restart_mean();
  }
}

void Lms200Emulator::restart_mean() noexcept {
  mean_taken_ = 0;
  mean_sum_.fill(0);
  mean_valid_.fill(0);
}

void Lms200Emulator::accumulate_mean(hal::Nanos now) noexcept {
  const hal::Nanos period = scan_period_ns(variant_);
  const std::int64_t newest = now / period - 1;
  if (newest <= last_scan_taken_) return;
  // After a long gap between steps only the last mean's worth of scans is taken.
  if (newest - last_scan_taken_ > mean_samples_) {
    last_scan_taken_ = newest - mean_samples_;
    restart_mean();
  }
  const MeasuringMode mode = measuring_mode();
  for (std::int64_t k = last_scan_taken_ + 1; k <= newest; ++k) {
    const std::size_t n = fill_words((k + 1) * period, words_, false);
    for (std::size_t i = 0; i < n; ++i) {
      const ScanValue v = decode_value(words_[i], mode);
      if (v.reason == InvalidReason::none) {
        mean_sum_[i] += v.distance;
        ++mean_valid_[i];
      } else {
        mean_code_[i] = v.distance;
      }
    }
    if (++mean_taken_ < mean_samples_) continue;
    // The mean of the valid samples; a beam without one keeps its last code.
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint16_t d = mean_valid_[i] > 0
                                  ? static_cast<std::uint16_t>((mean_sum_[i] + mean_valid_[i] / 2u) / mean_valid_[i])
                                  : mean_code_[i];
      mean_words_[i] = encode_value(d, 0, mode);
    }
    ++mean_blocks_;
    restart_mean();
  }
  last_scan_taken_ = newest;
}

void Lms200Emulator::enqueue_scan(hal::Nanos now, std::int64_t scan_number, bool streamed) noexcept {
  const OperatingMode kind = streamed ? mode_ : OperatingMode::continuous_all;
  std::size_t n = 0;
  if (kind == OperatingMode::mean_values) {
    n = value_count(variant_);
    std::copy_n(mean_words_.begin(), n, words_.begin());
  } else {
    // A scan on request (30 01) is a complete one even while partial scans stream.
    n = fill_words(now, words_, kind == OperatingMode::partial_scans);
  }
  const FaultPlan& f = options_.faults;
  const std::uint64_t k = counters_.scans_sent + 1;
  const MeasuringMode mode = measuring_mode();
  const ValueLayout layout = value_layout(mode);
  if (f.invalid_values_every != 0 && k % f.invalid_values_every == 0) {
    constexpr InvalidReason kCodes[] = {InvalidReason::not_valid, InvalidReason::dazzling,
                                        InvalidReason::operation_overflow, InvalidReason::snr_too_small,
                                        InvalidReason::channel1_error, InvalidReason::over_maximum};
    for (std::size_t i = 3, c = 0; i < n; i += 10, ++c)
      words_[i] = encode_value(code_value(kCodes[c % std::size(kCodes)], layout), 0, mode);
  }
  if (f.dazzle_every != 0 && k % f.dazzle_every == 0) {
    for (std::size_t i = 5; i < n; i += 10) {
      const ScanValue v = decode_value(words_[i], mode);
      words_[i] = encode_value(v.distance, value_flag::kDazzle, mode);
    }
  }
  // Which values go out: all of them, or the requested sub-range (clamped to the variant).
  std::size_t first = 0;
  if (kind == OperatingMode::subrange) {
    const std::size_t last = std::min<std::size_t>(subrange_last_, n);
    first = std::min<std::size_t>(subrange_first_, last) - 1;
    n = last - first;
  }
  // Header (B6: samples; B7: first, last), count word, values, optional indices.
  std::array<std::uint8_t, 4 + 2 + 2 * kMaxValues + 2> data{};
  std::size_t size = 0;
  std::uint8_t code = kReplyScan;
  if (kind == OperatingMode::mean_values) {
    code = kReplyMeanScan;
    data[size++] = mean_samples_;
  } else if (kind == OperatingMode::subrange) {
    code = kReplySubrangeScan;
    put_u16(&data[size], static_cast<std::uint16_t>(first + 1));
    put_u16(&data[size + 2], static_cast<std::uint16_t>(first + n));
    size += 4;
  }
  std::uint16_t count_word = static_cast<std::uint16_t>(n & 0x3FFu);
  count_word = static_cast<std::uint16_t>(count_word | (static_cast<unsigned>(units()) << 14));
  if (kind == OperatingMode::partial_scans) {
    count_word = static_cast<std::uint16_t>(count_word | 0x2000u | ((partial_offset_ & 0x3u) << 11));
  }
  put_u16(&data[size], count_word);
  size += 2;
  for (std::size_t i = 0; i < n; ++i, size += 2) put_u16(&data[size], words_[first + i]);
  if (config_[config_offset::kAvailability] & kAvailabilityRealTimeIndices) {
    data[size++] = static_cast<std::uint8_t>(scan_number & 0xFF);
    data[size++] = static_cast<std::uint8_t>(telegram_index_++ & 0xFF);
  }
  std::size_t frame_size = make_reply(code, {data.data(), size}, status_byte(), frame_, options_.address);
  if (f.false_header_every != 0 && k % f.false_header_every == 0) {
    // A plausible header whose claimed length swallows the real telegram's start.
    const std::uint8_t fake[] = {kStx, static_cast<std::uint8_t>(kReplyAddressFlag | options_.address), 0xD6, 0x02};
    enqueue(fake);
  }
  if (f.oversize_len_every != 0 && k % f.oversize_len_every == 0) {
    // A LEN no LMS200 telegram has; clients that trust it overrun their buffers.
    const std::uint8_t fake[] = {kStx, static_cast<std::uint8_t>(kReplyAddressFlag | options_.address), 0x36, 0x03};
    enqueue(fake);
  }
  if (f.corrupt_crc_every != 0 && k % f.corrupt_crc_every == 0) frame_[frame_size - 1] ^= 0x5A;
  if (f.truncate_every != 0 && k % f.truncate_every == 0) frame_size /= 2;
  enqueue({frame_.data(), frame_size});
  ++counters_.scans_sent;
  if (!streamed) return;
  if (last_scan_sent_ >= 0 && scan_number > last_scan_sent_ + 1)
    counters_.scans_skipped += static_cast<std::uint64_t>(scan_number - last_scan_sent_ - 1);
  last_scan_sent_ = scan_number;
  if (kind == OperatingMode::partial_scans) {
    const std::uint8_t steps = static_cast<std::uint8_t>(100 / variant_.resolution_cdeg);
    partial_offset_ = static_cast<std::uint8_t>((partial_offset_ + 100 / steps / 25) % 4);
  }
}

void Lms200Emulator::handle(hal::Nanos now, FrameView request) noexcept {
  const auto p = request.payload();
  const std::uint8_t cmd = p[0];
  if (counters_.requests < EmulatorCounters::kLoggedRequests)
    counters_.request_log[static_cast<std::size_t>(counters_.requests)] = static_cast<std::uint16_t>((cmd << 8) | (p.size() > 1 ? p[1] : 0));
  ++counters_.requests;
  auto reject = [this] {
    ++counters_.rejected;
    reply(kReplyRejected, {}, true);
  };
  switch (static_cast<Command>(cmd)) {
    case Command::mode_change: {
      if (p.size() < 2) return reject();
      const auto mode = static_cast<OperatingMode>(p[1]);
      std::uint8_t result = kModeChangeOk;
      switch (mode) {
        case OperatingMode::installation: {
          const std::string_view pw(reinterpret_cast<const char*>(p.data() + 2), p.size() - 2);
          if (pw == kDefaultPassword) {
            installation_ = true;
            mode_ = OperatingMode::monitoring;
          } else {
            result = kModeChangeBadPassword;
          }
          break;
        }
        case OperatingMode::diagnostic: break;
        case OperatingMode::monitoring:
          mode_ = mode;
          installation_ = false;
          break;
        case OperatingMode::continuous_all:
        case OperatingMode::partial_scans:
          start_stream(now, mode);
          break;
        case OperatingMode::mean_values:
          if (p.size() != 3 || p[2] < kMinMeanSamples || p[2] > kMaxMeanSamples) return reject();
          mean_samples_ = p[2];
          start_stream(now, mode);
          break;
        case OperatingMode::subrange: {
          if (p.size() != 6) return reject();
          const auto first = static_cast<std::uint16_t>(p[2] | (p[3] << 8));
          const auto last = static_cast<std::uint16_t>(p[4] | (p[5] << 8));
          if (first < 1 || first > last || last > value_count(variant_)) return reject();
          subrange_first_ = first;
          subrange_last_ = last;
          start_stream(now, mode);
          break;
        }
        case OperatingMode::baud_9600:
        case OperatingMode::baud_19200:
        case OperatingMode::baud_38400:
        case OperatingMode::baud_500000:
          pending_baud_ = baud_of_mode(mode);
          break;
        default: return reject();
      }
      const std::uint8_t data[] = {result};
      return reply(kReplyModeChange, data);
    }
    case Command::request_data: {
      if (p.size() != 2 || p[1] != 0x01) return reject();
      if (!options_.faults.suppress_ack) {
        const std::uint8_t a = kAck;
        enqueue({&a, 1});
      }
      return enqueue_scan(now, now / scan_period_ns(variant_) - 1, false);
    }
    case Command::status: {
      std::array<std::uint8_t, kStatusDataBytes> d{};  // index i here is status offset i + 1
      namespace o = status_offset;
      auto at = [&d](std::size_t offset) -> std::uint8_t& { return d[offset - 1]; };
      for (std::size_t i = 0; i < kSoftwareVersion.size(); ++i)
        at(o::kVersion + i) = static_cast<std::uint8_t>(kSoftwareVersion[i]);
      at(o::kOperatingMode) = static_cast<std::uint8_t>(installation_ ? OperatingMode::installation : mode_);
      at(o::kDeviceStatus) = device_status();
      at(o::kVariantType) = 0;
      at(o::kMeasuringMode) = config_[config_offset::kMeasuringMode];
      put_u16(&at(o::kScanAngle), variant_.angle_deg);
      put_u16(&at(o::kResolution), variant_.resolution_cdeg);
      put_u16(&at(o::kBaud), status_baud_word(baud_));
      at(o::kPermanentBaud) = options_.initial_baud != 9600 ? 1 : 0;
      at(o::kAddress) = options_.address;
      at(o::kUnits) = config_[config_offset::kUnits];
      at(kStatusLaserOn) = 1;
      for (std::size_t i = 0; i < kBootVersion.size(); ++i)
        at(kStatusBootVersion + i) = static_cast<std::uint8_t>(kBootVersion[i]);
      return reply(kReplyStatus, d);
    }
    case Command::errors: return reply(kReplyErrors, {});
    case Command::type:
      return reply(kReplyType, {reinterpret_cast<const std::uint8_t*>(kTypeString.data()), kTypeString.size()});
    case Command::variant: {
      if (p.size() != 5) return reject();
      const Variant wanted{static_cast<std::uint16_t>(p[1] | (p[2] << 8)),
                           static_cast<std::uint16_t>(p[3] | (p[4] << 8))};
      const bool ok = valid_variant(wanted);
      if (ok) variant_ = wanted;
      std::uint8_t d[5] = {static_cast<std::uint8_t>(ok ? 1 : 0)};
      put_u16(&d[1], variant_.angle_deg);
      put_u16(&d[3], variant_.resolution_cdeg);
      return reply(kReplyVariant, d);
    }
    case Command::read_config:
      return reply(kReplyReadConfig, {config_.data(), options_.short_config ? kConfigBytesShort : kConfigBytes});
    case Command::write_config: {
      const std::size_t n = p.size() - 1;
      if (n < kMinWriteConfigBytes || n > kConfigBytes) return reject();
      const bool ok = installation_ && valid_measuring_mode(p[1 + config_offset::kMeasuringMode]) &&
                      p[1 + config_offset::kUnits] <= static_cast<std::uint8_t>(Units::mm);
      if (ok) {
        std::copy_n(p.begin() + 1, n, config_.begin());
        ++counters_.config_writes;
      }
      config_reply_[0] = ok ? 1 : 0;
      std::copy_n(config_.begin(), n, config_reply_.begin() + 1);
      config_reply_size_ = n + 1;
      // ACK now; the F7 follows once the EEPROM write is done.
      if (!options_.faults.suppress_ack) {
        const std::uint8_t a = kAck;
        enqueue({&a, 1});
      }
      config_reply_at_ns_ = now + hal::millis(ok ? options_.config_write_delay_ms : 0);
      return;
    }
  }
  reject();
}

void Lms200Emulator::pace_output(hal::Nanos now, bool garble) noexcept {
  if (queued() == 0) {
    line_free_ns_ = std::max(line_free_ns_, now);
    return;
  }
  const hal::Nanos byte_ns = transmission_ns(1, baud_);
  if (now < line_free_ns_ + byte_ns) return;
  std::size_t due = static_cast<std::size_t>((now - line_free_ns_) / byte_ns);
  due = std::min(due, queued());
  std::array<std::uint8_t, 256> chunk;
  while (due > 0) {
    const std::size_t n = std::min(due, chunk.size());
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t b = queue_[(q_head_ + i) % kQueueBytes];
      // A receiver at another rate samples the wrong bits: deterministic nonsense.
      chunk[i] = garble ? static_cast<std::uint8_t>((b ^ 0xA5u) * 7u + 0x31u) : b;
    }
    Result<std::size_t> w = stream_.write({chunk.data(), n});
    if (!w || *w == 0) {
      // Client gone or not reading: the line stalls, nothing is lost.
      line_free_ns_ = now;
      return;
    }
    q_head_ += *w;
    line_free_ns_ += static_cast<hal::Nanos>(*w) * byte_ns;
    counters_.bytes_sent += *w;
    if (garble) counters_.garbled_tx_bytes += *w;
    due -= *w;
    if (*w < n) {
      line_free_ns_ = now;
      return;
    }
  }
}

void Lms200Emulator::step(hal::Nanos now) noexcept {
  now_ = now;
  const FaultPlan& f = options_.faults;
  bool garble = false;
  if (client_ != nullptr) {
    Result<std::uint32_t> b = client_->client_baud();
    garble = b && *b != baud_;
  }
  std::array<std::uint8_t, 512> chunk;
  for (int reads = 0; reads < 16; ++reads) {
    Result<std::size_t> n = stream_.read(chunk);
    if (!n || *n == 0) break;
    if (f.silent) continue;
    if (garble) {
      counters_.garbled_rx_bytes += *n;
      continue;
    }
    std::size_t offset = 0;
    while (offset < *n) {
      offset += parser_.push({chunk.data() + offset, *n - offset});
      const std::uint64_t crc_before = parser_.stats().crc_errors;
      TelegramParser::Event event;
      while (parser_.next(event)) {
        if (event.kind == TelegramParser::Kind::frame) handle(now, event.frame);
      }
      if (parser_.stats().crc_errors != crc_before) {
        ++counters_.naks_sent;
        const std::uint8_t nak = kNak;
        enqueue({&nak, 1});
      }
      if (parser_.free_space() == 0) parser_.reset();  // only garbage can fill it
    }
  }
  if (f.silent) {
    q_head_ = q_tail_;
    line_free_ns_ = now;
    return;
  }
  if (config_reply_at_ns_ >= 0 && now >= config_reply_at_ns_) {
    config_reply_at_ns_ = -1;
    reply(kReplyWriteConfig, {config_reply_.data(), config_reply_size_}, false);
  }
  pace_output(now, garble);
  // A baud change takes effect once its reply has left the line.
  if (pending_baud_ != 0 && queued() == 0 && now >= line_free_ns_) {
    baud_ = pending_baud_;
    pending_baud_ = 0;
    ++counters_.baud_changes;
  }
  // The mirror keeps turning whether or not the line is free: means add up every scan.
  if (mode_ == OperatingMode::mean_values) accumulate_mean(now);
  if (streaming() && queued() == 0 && config_reply_at_ns_ < 0) {
    // Mean values are numbered by finished means, the rest by scans in the stream's period.
    const std::int64_t newest = mode_ == OperatingMode::mean_values ? mean_blocks_ : now / stream_period_ns() - 1;
    if (newest > last_scan_sent_) {
      enqueue_scan(now, newest, true);
      pace_output(now, garble);
    }
  }
}

}  // namespace sen3bot::lms200
