#include "sen3bot/lms200/protocol.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::lms200 {

namespace {

std::uint16_t get_u16(std::span<const std::uint8_t> b, std::size_t at) noexcept {
  return static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8));
}

void put_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}

Error protocol_error(const char* what, std::uint8_t code, std::size_t len) {
  return Error::format(Errc::protocol, "lms200: %s (reply 0x%02X, LEN %zu)", what, code, len);
}

}  // namespace

Result<OperatingMode> baud_mode(std::uint32_t baud) noexcept {
  switch (baud) {
    case 9600: return OperatingMode::baud_9600;
    case 19200: return OperatingMode::baud_19200;
    case 38400: return OperatingMode::baud_38400;
    case 500000: return OperatingMode::baud_500000;
    default: return Error::format(Errc::invalid_argument, "lms200: unsupported baud %u", baud);
  }
}

std::uint32_t baud_of_mode(OperatingMode mode) noexcept {
  switch (mode) {
    case OperatingMode::baud_9600: return 9600;
    case OperatingMode::baud_19200: return 19200;
    case OperatingMode::baud_38400: return 38400;
    case OperatingMode::baud_500000: return 500000;
    default: return 0;
  }
}

std::uint16_t status_baud_word(std::uint32_t baud) noexcept {
  if (baud == 0) return 0;
  const auto divisor = static_cast<std::uint32_t>(std::lround(1e6 / baud));
  return static_cast<std::uint16_t>(0x8000u | ((divisor - 1u) & 0x7FFFu));
}

std::uint32_t baud_of_status_word(std::uint16_t word) noexcept {
  for (std::uint32_t b : kSupportedBauds)
    if (status_baud_word(b) == word) return b;
  return 0;
}

StatusLevel status_level(std::uint8_t status) noexcept {
  const unsigned level = status & 0x07u;
  return level <= static_cast<unsigned>(StatusLevel::fatal) ? static_cast<StatusLevel>(level) : StatusLevel::reserved;
}

std::uint8_t with_status_level(std::uint8_t status, StatusLevel level) noexcept {
  return static_cast<std::uint8_t>((status & ~0x07u) | (static_cast<unsigned>(level) & 0x07u));
}

bool valid_variant(Variant v) noexcept {
  if (v.angle_deg == 180) return v.resolution_cdeg == 100 || v.resolution_cdeg == 50;
  if (v.angle_deg == 100) return v.resolution_cdeg == 100 || v.resolution_cdeg == 50 || v.resolution_cdeg == 25;
  return false;
}

std::uint16_t value_count(Variant v) noexcept {
  if (v.resolution_cdeg == 0) return 0;
  return static_cast<std::uint16_t>(v.angle_deg * 100u / v.resolution_cdeg + 1u);
}

std::int64_t scan_period_ns(Variant v) noexcept {
  const std::int64_t revolutions = v.resolution_cdeg == 25 ? 4 : (v.resolution_cdeg == 50 ? 2 : 1);
  return revolutions * kMirrorPeriodNs;
}

std::string_view to_string(Units u) noexcept {
  switch (u) {
    case Units::cm: return "cm";
    case Units::mm: return "mm";
    case Units::dm: return "dm";
  }
  return "?";
}

double metres_per_unit(Units u) noexcept {
  switch (u) {
    case Units::cm: return 0.01;
    case Units::mm: return 0.001;
    case Units::dm: return 0.1;
  }
  return 0.01;
}

bool valid_measuring_mode(std::uint8_t mode) noexcept {
  return mode <= 0x06 || mode == 0x0F || mode == 0x3F;
}

ValueLayout value_layout(MeasuringMode mode) noexcept {
  std::uint16_t mask = 0x1FFF;
  switch (mode) {
    case MeasuringMode::range8_fields_dazzle:
    case MeasuringMode::range8_reflector8:
    case MeasuringMode::range8_fields_abc: mask = 0x1FFF; break;
    case MeasuringMode::range16_reflector4:
    case MeasuringMode::range16_fields_ab: mask = 0x3FFF; break;
    case MeasuringMode::range32_reflector2:
    case MeasuringMode::range32_field_a: mask = 0x7FFF; break;
    case MeasuringMode::range32_immediate:
    case MeasuringMode::reflectivity: mask = 0xFFFF; break;
  }
  return {mask, static_cast<std::uint16_t>(mask - 8u)};
}

std::string_view to_string(InvalidReason r) noexcept {
  switch (r) {
    case InvalidReason::none: return "none";
    case InvalidReason::not_valid: return "not_valid";
    case InvalidReason::dazzling: return "dazzling";
    case InvalidReason::operation_overflow: return "operation_overflow";
    case InvalidReason::snr_too_small: return "snr_too_small";
    case InvalidReason::channel1_error: return "channel1_error";
    case InvalidReason::over_maximum: return "over_maximum";
    case InvalidReason::reserved_code: return "reserved_code";
  }
  return "?";
}

InvalidReason classify(std::uint16_t distance, ValueLayout layout) noexcept {
  if (distance < layout.first_code) return InvalidReason::none;
  switch (layout.distance_mask - distance) {
    case 0: return InvalidReason::not_valid;
    case 1: return InvalidReason::dazzling;
    case 2: return InvalidReason::operation_overflow;
    case 4: return InvalidReason::snr_too_small;
    case 5: return InvalidReason::channel1_error;
    case 8: return InvalidReason::over_maximum;
    default: return InvalidReason::reserved_code;
  }
}

std::uint16_t code_value(InvalidReason r, ValueLayout layout) noexcept {
  int below = 0;
  switch (r) {
    case InvalidReason::none: return 0;
    case InvalidReason::not_valid: below = 0; break;
    case InvalidReason::dazzling: below = 1; break;
    case InvalidReason::operation_overflow: below = 2; break;
    case InvalidReason::snr_too_small: below = 4; break;
    case InvalidReason::channel1_error: below = 5; break;
    case InvalidReason::over_maximum: below = 8; break;
    case InvalidReason::reserved_code: below = 3; break;
  }
  return static_cast<std::uint16_t>(layout.distance_mask - below);
}

ScanValue decode_value(std::uint16_t word, MeasuringMode mode) noexcept {
  using namespace value_flag;
  const ValueLayout layout = value_layout(mode);
  ScanValue v;
  v.distance = static_cast<std::uint16_t>(word & layout.distance_mask);
  const unsigned high = word & ~layout.distance_mask & 0xFFFFu;
  std::uint8_t flags = 0;
  switch (mode) {
    case MeasuringMode::range8_fields_dazzle:
    case MeasuringMode::range8_fields_abc:
      if (high & 0x2000) flags |= kFieldA;
      if (high & 0x4000) flags |= kFieldB;
      if (high & 0x8000) flags |= mode == MeasuringMode::range8_fields_dazzle ? kDazzle : kFieldC;
      break;
    case MeasuringMode::range8_reflector8:
      flags |= static_cast<std::uint8_t>(((high >> 13) & 0x7u) << kReflectorShift);
      break;
    case MeasuringMode::range16_reflector4:
      flags |= static_cast<std::uint8_t>(((high >> 14) & 0x3u) << kReflectorShift);
      break;
    case MeasuringMode::range16_fields_ab:
      if (high & 0x4000) flags |= kFieldA;
      if (high & 0x8000) flags |= kFieldB;
      break;
    case MeasuringMode::range32_reflector2:
      if (high & 0x8000) flags |= static_cast<std::uint8_t>(1u << kReflectorShift);
      break;
    case MeasuringMode::range32_field_a:
      if (high & 0x8000) flags |= kFieldA;
      break;
    case MeasuringMode::range32_immediate:
    case MeasuringMode::reflectivity: break;
  }
  v.reason = classify(v.distance, layout);
  if (v.reason == InvalidReason::none) flags |= kValid;
  v.flags = flags;
  return v;
}

std::uint16_t encode_value(std::uint16_t distance, std::uint8_t flags, MeasuringMode mode) noexcept {
  using namespace value_flag;
  const ValueLayout layout = value_layout(mode);
  unsigned word = distance & layout.distance_mask;
  const unsigned level = flags >> kReflectorShift;
  switch (mode) {
    case MeasuringMode::range8_fields_dazzle:
    case MeasuringMode::range8_fields_abc:
      if (flags & kFieldA) word |= 0x2000;
      if (flags & kFieldB) word |= 0x4000;
      if (flags & (kDazzle | kFieldC)) word |= 0x8000;
      break;
    case MeasuringMode::range8_reflector8: word |= (level & 0x7u) << 13; break;
    case MeasuringMode::range16_reflector4: word |= (level & 0x3u) << 14; break;
    case MeasuringMode::range16_fields_ab:
      if (flags & kFieldA) word |= 0x4000;
      if (flags & kFieldB) word |= 0x8000;
      break;
    case MeasuringMode::range32_reflector2:
      if (level) word |= 0x8000;
      break;
    case MeasuringMode::range32_field_a:
      if (flags & kFieldA) word |= 0x8000;
      break;
    case MeasuringMode::range32_immediate:
    case MeasuringMode::reflectivity: break;
  }
  return static_cast<std::uint16_t>(word);
}

std::uint16_t crc16(std::span<const std::uint8_t> bytes) noexcept {
  constexpr std::uint16_t kPolynomial = 0x8005;
  std::uint16_t crc = 0;
  std::uint8_t previous = 0;
  for (std::uint8_t current : bytes) {
    const auto word = static_cast<std::uint16_t>(current | (previous << 8));
    previous = current;
    if (crc & 0x8000u) {
      crc = static_cast<std::uint16_t>(((crc & 0x7FFFu) << 1) ^ kPolynomial);
    } else {
      crc = static_cast<std::uint16_t>(crc << 1);
    }
    crc ^= word;
  }
  return crc;
}

Request make_request(std::span<const std::uint8_t> payload, std::uint8_t address) noexcept {
  Request r;
  const std::size_t n = std::min(payload.size(), kMaxRequestBytes - kFrameOverheadBytes);
  r.bytes[0] = kStx;
  r.bytes[1] = address;
  put_u16(&r.bytes[2], static_cast<std::uint16_t>(n));
  std::copy_n(payload.begin(), n, r.bytes.begin() + 4);
  const std::uint16_t crc = crc16({r.bytes.data(), n + 4});
  put_u16(&r.bytes[4 + n], crc);
  r.size = static_cast<std::uint8_t>(n + kFrameOverheadBytes);
  return r;
}

Request request_mode(OperatingMode mode) noexcept {
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::mode_change), static_cast<std::uint8_t>(mode)};
  return make_request(p);
}

Request request_installation_mode(std::string_view password) noexcept {
  std::array<std::uint8_t, 2 + kPasswordBytes> p{};
  p[0] = static_cast<std::uint8_t>(Command::mode_change);
  p[1] = static_cast<std::uint8_t>(OperatingMode::installation);
  for (std::size_t i = 0; i < kPasswordBytes; ++i)
    p[2 + i] = i < password.size() ? static_cast<std::uint8_t>(password[i]) : std::uint8_t{' '};
  return make_request(p);
}

Request request_baud(std::uint32_t baud) noexcept {
  const Result<OperatingMode> mode = baud_mode(baud);
  return request_mode(mode ? *mode : OperatingMode::baud_9600);
}

Request request_status() noexcept {
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::status)};
  return make_request(p);
}

Request request_errors() noexcept {
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::errors)};
  return make_request(p);
}

Request request_type() noexcept {
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::type)};
  return make_request(p);
}

Request request_variant(Variant v) noexcept {
  std::uint8_t p[5] = {static_cast<std::uint8_t>(Command::variant)};
  put_u16(&p[1], v.angle_deg);
  put_u16(&p[3], v.resolution_cdeg);
  return make_request(p);
}

Request request_read_config() noexcept {
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::read_config)};
  return make_request(p);
}

Request request_write_config(std::span<const std::uint8_t> block) noexcept {
  std::array<std::uint8_t, 1 + kConfigBytes> p{};
  p[0] = static_cast<std::uint8_t>(Command::write_config);
  const std::size_t n = std::min(block.size(), kConfigBytes);
  std::copy_n(block.begin(), n, p.begin() + 1);
  return make_request({p.data(), n + 1});
}

Request request_single_scan() noexcept {
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::request_data), 0x01};
  return make_request(p);
}

Result<Request> request_mean_values(std::uint8_t samples) noexcept {
  if (samples < kMinMeanSamples || samples > kMaxMeanSamples)
    return Error::format(Errc::invalid_argument, "lms200: mean values over %u scans; the LMS200 averages %u to %u",
                         samples, kMinMeanSamples, kMaxMeanSamples);
  const std::uint8_t p[] = {static_cast<std::uint8_t>(Command::mode_change),
                            static_cast<std::uint8_t>(OperatingMode::mean_values), samples};
  return make_request(p);
}

Result<Request> request_subrange(std::uint16_t first, std::uint16_t last, Variant variant) noexcept {
  if (!valid_variant(variant))
    return Error::format(Errc::invalid_argument, "lms200: sub-range for variant %u/%u, which the LMS200 does not have",
                         variant.angle_deg, variant.resolution_cdeg);
  const std::uint16_t n = value_count(variant);
  if (first < 1 || first > last || last > n)
    return Error::format(Errc::invalid_argument,
                         "lms200: sub-range %u..%u; need 1 <= first <= last <= %u (1-based, variant %u/%u)", first,
                         last, n, variant.angle_deg, variant.resolution_cdeg);
  std::uint8_t p[6] = {static_cast<std::uint8_t>(Command::mode_change),
                       static_cast<std::uint8_t>(OperatingMode::subrange)};
  put_u16(&p[2], first);
  put_u16(&p[4], last);
  return make_request(p);
}

std::size_t make_reply(std::uint8_t code, std::span<const std::uint8_t> data, std::uint8_t status,
                       std::span<std::uint8_t> out, std::uint8_t address) noexcept {
  const std::size_t len = data.size() + 2;
  const std::size_t total = len + kFrameOverheadBytes;
  if (out.size() < total || len > 0xFFFF) return 0;
  out[0] = kStx;
  out[1] = static_cast<std::uint8_t>(kReplyAddressFlag | address);
  put_u16(&out[2], static_cast<std::uint16_t>(len));
  out[4] = code;
  std::copy(data.begin(), data.end(), out.begin() + 5);
  out[4 + len - 1] = status;
  put_u16(&out[4 + len], crc16(out.first(4 + len)));
  return total;
}

Result<ModeChangeReply> decode_mode_change(FrameView f) noexcept {
  if (f.code() != kReplyModeChange || f.len() != 3) return protocol_error("not an A0 mode-change reply", f.code(), f.len());
  return ModeChangeReply{f.bytes[5], f.reply_status()};
}

Result<StatusReply> decode_status(FrameView f) noexcept {
  if (f.code() != kReplyStatus || f.len() != kStatusDataBytes + 2)
    return protocol_error("not a B1 status reply of 152 data bytes", f.code(), f.len());
  // Offsets count from the B1 code, as the drivers that documented them do.
  const std::span<const std::uint8_t> p = f.payload();
  namespace o = status_offset;
  StatusReply s;
  for (std::size_t i = 0; i < 7; ++i) {
    const std::uint8_t c = p[o::kVersion + i];
    s.software_version[i] = (c >= 0x20 && c < 0x7F) ? static_cast<char>(c) : '?';
  }
  s.operating_mode = p[o::kOperatingMode];
  s.device_status = p[o::kDeviceStatus];
  s.variant_type = p[o::kVariantType];
  s.measuring_mode = p[o::kMeasuringMode];
  s.variant.angle_deg = get_u16(p, o::kScanAngle);
  s.variant.resolution_cdeg = get_u16(p, o::kResolution);
  s.baud = baud_of_status_word(get_u16(p, o::kBaud));
  s.permanent_baud = p[o::kPermanentBaud];
  s.lms_address = p[o::kAddress];
  s.units = p[o::kUnits];
  s.status = f.reply_status();
  return s;
}

Result<TypeReply> decode_type(FrameView f) noexcept {
  if (f.code() != kReplyType || f.len() < 2) return protocol_error("not a BA type reply", f.code(), f.len());
  TypeReply t;
  const auto data = f.reply_data();
  const std::size_t n = std::min(data.size(), t.type.size() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t c = data[i];
    t.type[i] = (c >= 0x20 && c < 0x7F) ? static_cast<char>(c) : '?';
  }
  t.status = f.reply_status();
  return t;
}

Result<VariantReply> decode_variant(FrameView f) noexcept {
  if (f.code() != kReplyVariant || f.len() != 7) return protocol_error("not a BB variant reply", f.code(), f.len());
  const auto p = f.payload();
  VariantReply v;
  v.accepted = p[1] == 1;
  v.variant.angle_deg = get_u16(p, 2);
  v.variant.resolution_cdeg = get_u16(p, 4);
  v.status = f.reply_status();
  return v;
}

Result<ConfigReply> decode_read_config(FrameView f) noexcept {
  const std::size_t n = f.len() >= 2 ? f.len() - 2u : 0;
  if (f.code() != kReplyReadConfig || (n != kConfigBytes && n != kConfigBytesShort))
    return protocol_error("not an F4 configuration reply of 32 or 34 bytes", f.code(), f.len());
  ConfigReply c;
  const auto data = f.reply_data();
  std::copy(data.begin(), data.end(), c.block.bytes.begin());
  c.block.size = static_cast<std::uint8_t>(n);
  c.status = f.reply_status();
  return c;
}

Result<ConfigReply> decode_write_config(FrameView f) noexcept {
  // F7 ok, then the echoed block (any length up to 34).
  if (f.code() != kReplyWriteConfig || f.len() < 3 || f.len() > kConfigBytes + 3)
    return protocol_error("not an F7 configuration reply", f.code(), f.len());
  ConfigReply c;
  const auto data = f.reply_data();
  c.accepted = data[0] == 1;
  std::copy(data.begin() + 1, data.end(), c.block.bytes.begin());
  c.block.size = static_cast<std::uint8_t>(data.size() - 1);
  c.status = f.reply_status();
  return c;
}

namespace {

// The part B0, B6 and B7 share: the count word at payload offset `at`, the values, the
// optional real-time indices (told apart by LEN), the status byte.
Result<ScanTelegram> decode_values(FrameView f, std::size_t at, ScanTelegram& s, const char* name) noexcept {
  // Header fields before the count word, the count word itself and the status byte.
  const std::size_t fixed = at + 2 + 1;
  if (f.len() < fixed)
    return Error::format(Errc::protocol, "lms200: %s LEN %u too short for its header", name, f.len());
  const auto p = f.payload();
  const std::uint16_t count_word = get_u16(p, at);
  s.count = count_word & 0x03FFu;
  s.partial_offset_qdeg = static_cast<std::uint8_t>((count_word >> 11) & 0x3u);
  s.partial = (count_word & 0x2000u) != 0;
  const unsigned units = count_word >> 14;
  if (units > 2) return Error::format(Errc::protocol, "lms200: %s units bits 11 are reserved", name);
  s.units = static_cast<Units>(units);
  if (s.count > kMaxValues) return Error::format(Errc::protocol, "lms200: %s count %u above 401", name, s.count);
  const std::size_t plain = 2u * s.count + fixed;
  if (f.len() == plain) {
    s.has_indices = false;
  } else if (f.len() == plain + 2) {
    s.has_indices = true;
  } else {
    return Error::format(Errc::protocol, "lms200: %s LEN %u does not fit %u values", name, f.len(), s.count);
  }
  const std::size_t values_at = at + 2;
  for (std::size_t i = 0; i < s.count; ++i) s.words[i] = get_u16(p, values_at + 2 * i);
  if (s.has_indices) {
    s.scan_index = p[values_at + 2u * s.count];
    s.telegram_index = p[values_at + 2u * s.count + 1];
  }
  s.status = f.reply_status();
  return s;
}

}  // namespace

Result<ScanTelegram> decode_scan(FrameView f) noexcept {
  if (f.code() != kReplyScan || f.len() < 4) return protocol_error("not a B0 scan reply", f.code(), f.len());
  ScanTelegram s;
  Result<ScanTelegram> r = decode_values(f, 1, s, "B0");
  if (r) {
    r->code = kReplyScan;
    r->last_index = r->count;
  }
  return r;
}

Result<ScanTelegram> decode_mean_scan(FrameView f) noexcept {
  if (f.code() != kReplyMeanScan) return protocol_error("not a B6 mean-value reply", f.code(), f.len());
  if (f.len() < 5) return Error::format(Errc::protocol, "lms200: B6 LEN %u too short for its header", f.len());
  ScanTelegram s;
  s.code = kReplyMeanScan;
  s.mean_samples = f.payload()[1];
  if (s.mean_samples < kMinMeanSamples || s.mean_samples > kMaxMeanSamples)
    return Error::format(Errc::protocol, "lms200: B6 mean over %u scans, outside %u..%u", s.mean_samples,
                         kMinMeanSamples, kMaxMeanSamples);
  Result<ScanTelegram> r = decode_values(f, 2, s, "B6");
  if (r) r->last_index = r->count;
  return r;
}

Result<ScanTelegram> decode_subrange_scan(FrameView f) noexcept {
  if (f.code() != kReplySubrangeScan) return protocol_error("not a B7 sub-range reply", f.code(), f.len());
  if (f.len() < 8) return Error::format(Errc::protocol, "lms200: B7 LEN %u too short for its header", f.len());
  const auto p = f.payload();
  ScanTelegram s;
  s.code = kReplySubrangeScan;
  s.first_index = get_u16(p, 1);
  s.last_index = get_u16(p, 3);
  if (s.first_index < 1 || s.first_index > s.last_index || s.last_index > kMaxValues)
    return Error::format(Errc::protocol, "lms200: B7 sub-range %u..%u is not 1 <= first <= last <= 401",
                         s.first_index, s.last_index);
  Result<ScanTelegram> r = decode_values(f, 5, s, "B7");
  if (r && r->count != r->last_index - r->first_index + 1)
    return Error::format(Errc::protocol, "lms200: B7 sub-range %u..%u but %u values", r->first_index, r->last_index,
                         r->count);
  return r;
}

Result<ScanTelegram> decode_any_scan(FrameView f) noexcept {
  switch (f.code()) {
    case kReplyScan: return decode_scan(f);
    case kReplyMeanScan: return decode_mean_scan(f);
    case kReplySubrangeScan: return decode_subrange_scan(f);
    default: return protocol_error("not a scan reply (B0, B6, B7)", f.code(), f.len());
  }
}

}  // namespace sen3bot::lms200
