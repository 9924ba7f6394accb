#include "sen3bot/lms200/capture_decode.hpp"

#include <cmath>

#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {

namespace {

void print_hex(std::FILE* out, std::span<const std::uint8_t> bytes) {
  std::fputc('"', out);
  for (std::uint8_t b : bytes) std::fprintf(out, "%02x", b);
  std::fputc('"', out);
}

struct Decoder {
  std::FILE* out = nullptr;
  MeasuringMode mode = MeasuringMode::range8_fields_dazzle;
  CaptureDecodeSummary summary;

  void request(double t_s, FrameView f) {
    ++summary.requests;
    std::fprintf(out, "{\"t_s\":%.6f,\"dir\":\"tx\",\"cmd\":\"0x%02x\",\"len\":%u,\"bytes\":", t_s, f.code(), f.len());
    print_hex(out, f.bytes);
    std::fputs("}\n", out);
    // A configuration write changes how later scans are read.
    if (f.code() == static_cast<std::uint8_t>(Command::write_config) && f.len() > 1 + config_offset::kMeasuringMode) {
      const std::uint8_t m = f.payload()[1 + config_offset::kMeasuringMode];
      if (valid_measuring_mode(m)) mode = static_cast<MeasuringMode>(m);
    }
  }

  void reply(double t_s, FrameView f) {
    std::fprintf(out, "{\"t_s\":%.6f,\"dir\":\"rx\",\"code\":\"0x%02x\",\"status\":\"0x%02x\"", t_s, f.code(),
                 f.reply_status());
    switch (f.code()) {
      case kReplyModeChange:
        if (auto r = decode_mode_change(f)) std::fprintf(out, ",\"result\":%u", r->result);
        break;
      case kReplyStatus:
        if (auto r = decode_status(f))
          std::fprintf(out, ",\"version\":\"%s\",\"mode\":\"0x%02x\",\"angle_deg\":%u,\"resolution_cdeg\":%u,\"baud\":%u",
                       r->software_version.data(), r->operating_mode, r->variant.angle_deg,
                       r->variant.resolution_cdeg, r->baud);
        break;
      case kReplyType:
        if (auto r = decode_type(f)) std::fprintf(out, ",\"type\":\"%s\"", r->type.data());
        break;
      case kReplyVariant:
        if (auto r = decode_variant(f))
          std::fprintf(out, ",\"accepted\":%s,\"angle_deg\":%u,\"resolution_cdeg\":%u", r->accepted ? "true" : "false",
                       r->variant.angle_deg, r->variant.resolution_cdeg);
        break;
      case kReplyReadConfig:
      case kReplyWriteConfig: {
        auto r = f.code() == kReplyReadConfig ? decode_read_config(f) : decode_write_config(f);
        if (r) {
          std::fprintf(out, ",\"accepted\":%s,\"config_bytes\":%u,\"units\":%u,\"measuring_mode\":\"0x%02x\"",
                       r->accepted ? "true" : "false", r->block.size, r->block.units(), r->block.measuring_mode());
          if (valid_measuring_mode(r->block.measuring_mode()) && r->block.size > config_offset::kUnits)
            mode = static_cast<MeasuringMode>(r->block.measuring_mode());
        }
        break;
      }
      case kReplyScan:
      case kReplyMeanScan:
      case kReplySubrangeScan: scan(f); break;
      default: break;
    }
    std::fputs("}\n", out);
    ++summary.replies;
  }

  void scan(FrameView f) {
    Result<ScanTelegram> s = decode_any_scan(f);
    if (!s) {
      std::fprintf(out, ",\"error\":\"%s\"", s.error().c_str());
      return;
    }
    ++summary.scans;
    const double unit = metres_per_unit(s->units);
    std::fprintf(out, ",\"count\":%u,\"units\":\"%s\",\"partial\":%s,\"offset_qdeg\":%u,\"measuring_mode\":\"0x%02x\"",
                 s->count, to_string(s->units).data(), s->partial ? "true" : "false", s->partial_offset_qdeg,
                 static_cast<unsigned>(mode));
    if (s->code == kReplyMeanScan) std::fprintf(out, ",\"mean_samples\":%u", s->mean_samples);
    if (s->code == kReplySubrangeScan) std::fprintf(out, ",\"first\":%u,\"last\":%u", s->first_index, s->last_index);
    if (s->has_indices) std::fprintf(out, ",\"scan_index\":%u,\"telegram_index\":%u", s->scan_index, s->telegram_index);
    std::fputs(",\"ranges_m\":[", out);
    for (std::size_t i = 0; i < s->count; ++i) {
      const ScanValue v = decode_value(s->words[i], mode);
      if (i) std::fputc(',', out);
      if (v.reason == InvalidReason::none) {
        std::fprintf(out, "%.3f", v.distance * unit);
      } else {
        std::fputs("null", out);
      }
    }
    std::fputs("],\"invalid\":{", out);
    bool first = true;
    for (std::size_t i = 0; i < s->count; ++i) {
      const ScanValue v = decode_value(s->words[i], mode);
      if (v.reason == InvalidReason::none) continue;
      std::fprintf(out, "%s\"%zu\":\"%s\"", first ? "" : ",", i, to_string(v.reason).data());
      first = false;
    }
    std::fputc('}', out);
  }
};

}  // namespace

Result<CaptureDecodeSummary> decode_capture_json(const capture::CaptureFile& capture, std::string_view channel_name,
                                                 std::FILE* out) {
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
        std::fprintf(out, "{\"t_s\":%.6f,\"dir\":\"rx\",\"%s\":true}\n", t_s, ack ? "ack" : "nak");
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
        std::fprintf(out, "{\"t_s\":%.6f,\"event\":\"baud\",\"baud\":%u}\n", t_s, r.baud);
        break;
      default: break;
    }
  }
  d.summary.crc_errors = rx.stats().crc_errors;
  d.summary.garbage_bytes = rx.stats().garbage_bytes + stray_bytes;
  return d.summary;
}

}  // namespace sen3bot::lms200
