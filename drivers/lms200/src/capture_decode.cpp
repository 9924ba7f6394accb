#include "sen3bot/lms200/capture_decode.hpp"

#include <cmath>
#include <cstdarg>
#include <limits>
#include <vector>

#include "sen3bot/lms200/device.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {

namespace {

// fprintf, or nothing without a stream (for_each_scan decodes without printing).
[[gnu::format(printf, 2, 3)]] void put(std::FILE* out, const char* format, ...) {
  if (out == nullptr) return;
  va_list args;
  va_start(args, format);
  std::vfprintf(out, format, args);
  va_end(args);
}

void print_hex(std::FILE* out, std::span<const std::uint8_t> bytes) {
  put(out, "%c", '"');
  for (std::uint8_t b : bytes) put(out, "%02x", b);
  put(out, "%c", '"');
}

struct Decoder {
  std::FILE* out = nullptr;
  MeasuringMode mode = MeasuringMode::range8_fields_dazzle;
  CaptureDecodeSummary summary;
  const ScanVisitor* visit = nullptr;
  std::uint32_t baud = 9600;  // the LMS200's power-up rate, until the capture records a change
  std::vector<float> ranges;

  void request(double t_s, FrameView f) {
    ++summary.requests;
    put(out, "{\"t_s\":%.6f,\"dir\":\"tx\",\"cmd\":\"0x%02x\",\"len\":%u,\"bytes\":", t_s, f.code(), f.len());
    print_hex(out, f.bytes);
    put(out, "%s", "}\n");
    // A configuration write changes how later scans are read.
    if (f.code() == static_cast<std::uint8_t>(Command::write_config) && f.len() > 1 + config_offset::kMeasuringMode) {
      const std::uint8_t m = f.payload()[1 + config_offset::kMeasuringMode];
      if (valid_measuring_mode(m)) mode = static_cast<MeasuringMode>(m);
    }
  }

  void reply(double t_s, FrameView f) {
    put(out, "{\"t_s\":%.6f,\"dir\":\"rx\",\"code\":\"0x%02x\",\"status\":\"0x%02x\"", t_s, f.code(),
             f.reply_status());
    switch (f.code()) {
      case kReplyModeChange:
        if (auto r = decode_mode_change(f)) put(out, ",\"result\":%u", r->result);
        break;
      case kReplyStatus:
        if (auto r = decode_status(f))
          put(out, ",\"version\":\"%s\",\"mode\":\"0x%02x\",\"angle_deg\":%u,\"resolution_cdeg\":%u,\"baud\":%u",
              r->software_version.data(), r->operating_mode, r->variant.angle_deg,
              r->variant.resolution_cdeg, r->baud);
        break;
      case kReplyType:
        if (auto r = decode_type(f)) put(out, ",\"type\":\"%s\"", r->type.data());
        break;
      case kReplyVariant:
        if (auto r = decode_variant(f))
          put(out, ",\"accepted\":%s,\"angle_deg\":%u,\"resolution_cdeg\":%u", r->accepted ? "true" : "false",
              r->variant.angle_deg, r->variant.resolution_cdeg);
        break;
      case kReplyReadConfig:
      case kReplyWriteConfig: {
        auto r = f.code() == kReplyReadConfig ? decode_read_config(f) : decode_write_config(f);
        if (r) {
          put(out, ",\"accepted\":%s,\"config_bytes\":%u,\"units\":%u,\"measuring_mode\":\"0x%02x\"",
              r->accepted ? "true" : "false", r->block.size, r->block.units(), r->block.measuring_mode());
          if (valid_measuring_mode(r->block.measuring_mode()) && r->block.size > config_offset::kUnits)
            mode = static_cast<MeasuringMode>(r->block.measuring_mode());
        }
        break;
      }
      case kReplyScan:
      case kReplyMeanScan:
      case kReplySubrangeScan: scan(t_s, f); break;
      default: break;
    }
    put(out, "%s", "}\n");
    ++summary.replies;
  }

  void scan(double t_s, FrameView f) {
    Result<ScanTelegram> s = decode_any_scan(f);
    if (!s) {
      put(out, ",\"error\":\"%s\"", s.error().c_str());
      return;
    }
    ++summary.scans;
    const double unit = metres_per_unit(s->units);
    if (visit != nullptr) visit_scan(t_s, f, *s, unit);
    put(out, ",\"count\":%u,\"units\":\"%s\",\"partial\":%s,\"offset_qdeg\":%u,\"measuring_mode\":\"0x%02x\"",
             s->count, to_string(s->units).data(), s->partial ? "true" : "false", s->partial_offset_qdeg,
             static_cast<unsigned>(mode));
    if (s->code == kReplyMeanScan) put(out, ",\"mean_samples\":%u", s->mean_samples);
    if (s->code == kReplySubrangeScan) put(out, ",\"first\":%u,\"last\":%u", s->first_index, s->last_index);
    if (s->has_indices) put(out, ",\"scan_index\":%u,\"telegram_index\":%u", s->scan_index, s->telegram_index);
    put(out, "%s", ",\"ranges_m\":[");
    for (std::size_t i = 0; i < s->count; ++i) {
      const ScanValue v = decode_value(s->words[i], mode);
      if (i) put(out, "%c", ',');
      if (v.reason == InvalidReason::none) {
        put(out, "%.3f", v.distance * unit);
      } else {
        put(out, "%s", "null");
      }
    }
    put(out, "%s", "],\"invalid\":{");
    bool first = true;
    for (std::size_t i = 0; i < s->count; ++i) {
      const ScanValue v = decode_value(s->words[i], mode);
      if (v.reason == InvalidReason::none) continue;
      put(out, "%s\"%zu\":\"%s\"", first ? "" : ",", i, to_string(v.reason).data());
      first = false;
    }
    put(out, "%c", '}');
  }

  void visit_scan(double t_s, FrameView f, const ScanTelegram& s, double unit) {
    if (s.partial || s.code == kReplySubrangeScan) return;
    Variant v;
    bool known = false;
    for (const Variant candidate : {Variant{180, 100}, Variant{180, 50}, Variant{100, 100}, Variant{100, 50},
                                    Variant{100, 25}}) {
      if (value_count(candidate) != s.count) continue;
      v = candidate;
      known = true;
    }
    if (!known) return;
    ranges.assign(s.count, std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < s.count; ++i) {
      const ScanValue value = decode_value(s.words[i], mode);
      if (value.reason == InvalidReason::none) ranges[i] = static_cast<float>(value.distance * unit);
    }
    constexpr double kRadPerCdeg = 3.14159265358979323846 / 18000.0;
    CapturedScan scan;
    scan.t_s = t_s - hal::to_seconds(transmission_ns(f.bytes.size(), baud));
    scan.ranges_m = ranges;
    scan.angle_min_rad = -0.5 * v.angle_deg * 100.0 * kRadPerCdeg;
    scan.increment_rad = v.resolution_cdeg * kRadPerCdeg;
    (*visit)(scan);
  }
};

}  // namespace

static Result<CaptureDecodeSummary> walk(const capture::CaptureFile& capture, std::string_view channel_name, std::FILE* out,
                                  const ScanVisitor* visit) {
  const capture::ChannelDecl* channel = nullptr;
  for (const capture::ChannelDecl& c : capture.info().channels) {
    if (channel_name.empty() ? c.name.find("lms") != std::string::npos : c.name == channel_name) {
      channel = &c;
      break;
    }
  }
  if (channel == nullptr) return Error(Errc::not_found, "lms200: the capture has no LMS200 channel");
  Decoder d;
  d.out = out;
  d.visit = visit;
  if (channel->baud != 0) d.baud = channel->baud;
  // 0x06 / 0x15 mean ACK / NAK only while a request waits for its reply; elsewhere they are
  // bytes of broken telegrams.
  bool awaiting_reply = false;
  std::uint64_t stray_bytes = 0;
  TelegramParser rx(Side::from_device);
  TelegramParser tx(Side::from_host);
  auto drain = [&](TelegramParser& p, double t_s, bool from_device) {
    TelegramParser::Event e;
    while (p.next(e)) {
      if (e.kind == TelegramParser::Kind::frame) {
        if (from_device) {
          if (e.frame.code() != kReplyScan) awaiting_reply = false;
          d.reply(t_s, e.frame);
        } else {
          awaiting_reply = true;
          d.request(t_s, e.frame);
        }
      } else if (from_device && !awaiting_reply) {
        ++stray_bytes;
      } else if (from_device) {
        const bool ack = e.kind == TelegramParser::Kind::ack;
        ++(ack ? d.summary.acks : d.summary.naks);
        put(out, "{\"t_s\":%.6f,\"dir\":\"rx\",\"%s\":true}\n", t_s, ack ? "ack" : "nak");
      }
    }
  };
  auto feed = [&](TelegramParser& p, std::span<const std::uint8_t> bytes, double t_s, bool from_device) {
    while (!bytes.empty()) {
      const std::size_t n = p.push(bytes);
      bytes = bytes.subspan(n);
      drain(p, t_s, from_device);
      if (n == 0 && !bytes.empty()) p.drop_partial();
    }
  };
  for (const capture::Record& r : capture.records()) {
    if (r.channel != channel->id) continue;
    const double t_s = hal::to_seconds(r.t_ns);
    switch (r.kind) {
      case capture::RecordKind::rx: feed(rx, r.payload, t_s, true); break;
      case capture::RecordKind::tx: feed(tx, r.payload, t_s, false); break;
      case capture::RecordKind::baud_change:
        // Bytes of a telegram cut by the switch will never complete.
        rx.reset();
        d.baud = r.baud;
        put(out, "{\"t_s\":%.6f,\"event\":\"baud\",\"baud\":%u}\n", t_s, r.baud);
        break;
      default: break;
    }
  }
  d.summary.crc_errors = rx.stats().crc_errors;
  d.summary.garbage_bytes = rx.stats().garbage_bytes + stray_bytes;
  return d.summary;
}

Result<CaptureDecodeSummary> decode_capture_json(const capture::CaptureFile& capture, std::string_view channel_name,
                                                 std::FILE* out) {
  return walk(capture, channel_name, out, nullptr);
}

Result<CaptureDecodeSummary> for_each_scan(const capture::CaptureFile& capture, std::string_view channel_name,
                                           const ScanVisitor& visit) {
  return walk(capture, channel_name, nullptr, &visit);
}

}  // namespace sen3bot::lms200
