#include "sen3bot/lms200/capture_decode.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "sen3bot/json/json.hpp"

#include "sen3bot/lms200/device.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {

namespace {

std::string hex(std::span<const std::uint8_t> bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string text;
  for (const std::uint8_t b : bytes) {
    text += kHex[b >> 4];
    text += kHex[b & 0xF];
  }
  return text;
}

std::string hex_byte(unsigned value) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02x", value);
  return text;
}

// A fixed-size text field up to its first NUL.
template <std::size_t N>
std::string_view text_field(const std::array<char, N>& field) {
  std::size_t n = 0;
  while (n < N && field[n] != '\0') ++n;
  return {field.data(), n};
}

// One JSON object a line on `out`, or nothing without a stream (for_each_scan decodes without
// printing).
void print_line(std::FILE* out, const auto& write) {
  if (out == nullptr) return;
  json::FileSink sink(out);
  json::Writer w(sink);
  w.begin_object();
  write(w);
  w.end_object();
  std::fputc('\n', out);
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
    print_line(out, [&](json::Writer& w) {
      w.key("t_s").fixed_or_null(t_s, 6)
          .member("dir", "tx")
          .member("cmd", hex_byte(f.code()))
          .member_uint32("len", f.len())
          .member("bytes", hex(f.bytes));
    });
    // A configuration write changes how later scans are read.
    if (f.code() == static_cast<std::uint8_t>(Command::write_config) && f.len() > 1 + config_offset::kMeasuringMode) {
      const std::uint8_t m = f.payload()[1 + config_offset::kMeasuringMode];
      if (valid_measuring_mode(m)) mode = static_cast<MeasuringMode>(m);
    }
  }

  void reply(double t_s, FrameView f) {
    // Decoded (and visited) whether or not it is printed; printed with the mode it was read in.
    const MeasuringMode read_mode = mode;
    Result<ScanTelegram> telegram = Error(Errc::not_found, "not a scan");
    const bool is_scan = f.code() == kReplyScan || f.code() == kReplyMeanScan || f.code() == kReplySubrangeScan;
    if (is_scan) {
      telegram = decode_any_scan(f);
      if (telegram) {
        ++summary.scans;
        if (visit != nullptr) visit_scan(t_s, f, *telegram, metres_per_unit(telegram->units));
      }
    }
    print_line(out, [&](json::Writer& w) {
      w.key("t_s").fixed_or_null(t_s, 6)
          .member("dir", "rx")
          .member("code", hex_byte(f.code()))
          .member("status", hex_byte(f.reply_status()));
      switch (f.code()) {
        case kReplyModeChange:
          if (auto r = decode_mode_change(f)) w.member_uint32("result", r->result);
          break;
        case kReplyStatus:
          if (auto r = decode_status(f))
            w.member("version", text_field(r->software_version))
                .member("mode", hex_byte(r->operating_mode))
                .member_uint32("angle_deg", r->variant.angle_deg)
                .member_uint32("resolution_cdeg", r->variant.resolution_cdeg)
                .member_uint32("baud", r->baud);
          break;
        case kReplyType:
          if (auto r = decode_type(f)) w.member("type", text_field(r->type));
          break;
        case kReplyVariant:
          if (auto r = decode_variant(f))
            w.member_bool("accepted", r->accepted)
                .member_uint32("angle_deg", r->variant.angle_deg)
                .member_uint32("resolution_cdeg", r->variant.resolution_cdeg);
          break;
        case kReplyReadConfig:
        case kReplyWriteConfig: {
          auto r = f.code() == kReplyReadConfig ? decode_read_config(f) : decode_write_config(f);
          if (r)
            w.member_bool("accepted", r->accepted)
                .member_uint32("config_bytes", r->block.size)
                .member_uint32("units", r->block.units())
                .member("measuring_mode", hex_byte(r->block.measuring_mode()));
          break;
        }
        default:
          if (is_scan) print_scan(w, telegram, read_mode);
          break;
      }
    });
    if (f.code() == kReplyReadConfig || f.code() == kReplyWriteConfig) {
      auto r = f.code() == kReplyReadConfig ? decode_read_config(f) : decode_write_config(f);
      if (r && valid_measuring_mode(r->block.measuring_mode()) && r->block.size > config_offset::kUnits)
        mode = static_cast<MeasuringMode>(r->block.measuring_mode());
    }
    ++summary.replies;
  }

  static void print_scan(json::Writer& w, const Result<ScanTelegram>& s, MeasuringMode mode) {
    if (!s) {
      w.member("error", s.error().message());
      return;
    }
    const double unit = metres_per_unit(s->units);
    w.member_uint32("count", s->count)
        .member("units", to_string(s->units))
        .member_bool("partial", s->partial)
        .member_uint32("offset_qdeg", s->partial_offset_qdeg)
        .member("measuring_mode", hex_byte(static_cast<unsigned>(mode)));
    if (s->code == kReplyMeanScan) w.member_uint32("mean_samples", s->mean_samples);
    if (s->code == kReplySubrangeScan) w.member_uint32("first", s->first_index).member_uint32("last", s->last_index);
    if (s->has_indices) w.member_uint32("scan_index", s->scan_index).member_uint32("telegram_index", s->telegram_index);
    w.key("ranges_m").begin_array();
    for (std::size_t i = 0; i < s->count; ++i) {
      const ScanValue v = decode_value(s->words[i], mode);
      if (v.reason == InvalidReason::none) w.fixed_or_null(v.distance * unit, 3);
      else w.null();
    }
    w.end_array().key("invalid").begin_object();
    for (std::size_t i = 0; i < s->count; ++i) {
      const ScanValue v = decode_value(s->words[i], mode);
      if (v.reason != InvalidReason::none) w.member(std::to_string(i), to_string(v.reason));
    }
    w.end_object();
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
        print_line(out, [&](json::Writer& w) { w.key("t_s").fixed_or_null(t_s, 6).member("dir", "rx").member_bool(ack ? "ack" : "nak", true); });
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
        print_line(out, [&](json::Writer& w) { w.key("t_s").fixed_or_null(t_s, 6).member("event", "baud").member_uint32("baud", r.baud); });
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
