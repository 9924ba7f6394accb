#include "sen3bot/p2os/describe.hpp"

#include <string_view>

#include "sen3bot/json/json.hpp"

namespace sen3bot::p2os {

namespace {

// A NUL-terminated field of at most `capacity` bytes.
std::string_view field(const char* value, std::size_t capacity) {
  std::size_t n = 0;
  while (n < capacity && value[n] != '\0') ++n;
  return {value, n};
}

void describe_command(json::Writer& w, const Frame& frame) {
  w.member("type", command_name(frame.type)).member_uint32("cmd", frame.type);
  const CommandArgument arg = decode_argument(frame.payload);
  if (arg.kind == ArgKind::integer) {
    w.member_int64("arg", arg.value);
    if (frame.type == static_cast<std::uint8_t>(Command::vel2)) {
      const Vel2Units units = decode_vel2(arg);
      w.member_int64("left", units.left).member_int64("right", units.right);
    }
  } else if (arg.kind == ArgKind::string) {
    static constexpr char kHex[] = "0123456789abcdef";
    std::string hex;
    for (const std::uint8_t b : arg.text) {
      hex += kHex[b >> 4];
      hex += kHex[b & 0xF];
    }
    w.member("text", hex);
  }
}

void describe_server(json::Writer& w, const Frame& frame) {
  w.member("type", server_type_name(frame.type)).member_uint32("code", frame.type);
  if (auto sip = decode_sip(frame)) {
    w.member_bool("moving", sip->moving)
        .member_uint32("x", sip->x_raw)
        .member_uint32("y", sip->y_raw)
        .member_int64("th", sip->theta_raw)
        .member_int64("lvel", sip->left_vel_mm_s)
        .member_int64("rvel", sip->right_vel_mm_s)
        .member_uint32("battery_dv", sip->battery_dv)
        .member_uint32("stallbump", sip->stall_bumpers)
        .member_int64("control", sip->control_raw)
        .member_uint32("flags", sip->flags)
        .member_uint32("compass", sip->compass_2deg)
        .member_uint32("sonar", sip->sonar_count);
    if (sip->has_rot_vel) w.member_int64("rotvel_ddeg_s", sip->rot_vel_ddeg_s);
    if (sip->has_battery_x10) w.member_uint32("battery_x10", sip->battery_x10);
    return;
  }
  if (auto reply = decode_sync2_reply(frame)) {
    w.member("name", field(reply->name.data(), reply->name.size()))
        .member("class", field(reply->robot_class.data(), reply->robot_class.size()))
        .member("subclass", field(reply->subclass.data(), reply->subclass.size()));
    return;
  }
  if (auto config = decode_config(frame)) {
    w.member("class", field(config->robot_class.data(), config->robot_class.size()))
        .member("subclass", field(config->subclass.data(), config->subclass.size()))
        .member("serial", field(config->serial.data(), config->serial.size()))
        .member("name", field(config->name.data(), config->name.size()))
        .member_uint32("sip_cycle_ms", config->sip_cycle_ms)
        .member_uint32("watchdog_ms", config->watchdog_ms)
        .member_uint32("auto_baud", config->auto_baud)
        .member_uint32("trans_vel_max", config->trans_vel_max_mm_s)
        .member_uint32("rot_vel_max", config->rot_vel_max_deg_s);
    return;
  }
  if (auto enc = decode_encoder(frame)) {
    w.member_int64("left_ticks", enc->left_ticks).member_int64("right_ticks", enc->right_ticks);
    return;
  }
  if (frame.type == kTypeSipStopped || frame.type == kTypeSipMoving) w.member_bool("malformed", true);
}

}  // namespace

std::string describe_packet_json(double t_s, PacketDirection direction, const Frame& frame) {
  std::string out;
  out.reserve(256);
  json::StringSink sink(out);
  json::Writer w(sink);
  w.begin_object().key("t_s").fixed_or_null(t_s, 6).member("dir", direction == PacketDirection::to_robot ? "tx" : "rx");
  if (direction == PacketDirection::to_robot) {
    describe_command(w, frame);
  } else {
    describe_server(w, frame);
  }
  w.member_uint64("bytes", frame.raw.size()).end_object();
  return out;
}

Status decode_capture(const capture::CaptureFile& capture, std::string_view channel_name,
                      const std::function<void(const std::string& line)>& emit) {
  const capture::ChannelDecl* channel = nullptr;
  if (!channel_name.empty()) {
    channel = capture.find_channel(channel_name);
  } else {
    channel = capture.find_channel("p2os");
    if (channel == nullptr && capture.info().channels.size() == 1) channel = &capture.info().channels.front();
  }
  if (channel == nullptr) {
    return Error::format(Errc::not_found, "capture has no channel '%.*s'",
                         static_cast<int>(channel_name.empty() ? 4 : channel_name.size()),
                         channel_name.empty() ? "p2os" : channel_name.data());
  }
  // Time stamps in the capture are exact; the parsers' gap rule uses them too.
  FrameParser rx_parser;
  FrameParser tx_parser;
  for (const capture::Record& record : capture.records()) {
    if (record.channel != channel->id) continue;
    const double t_s = hal::to_seconds(record.t_ns);
    if (record.kind == capture::RecordKind::rx) {
      rx_parser.feed(record.payload, record.t_ns,
                     [&](const Frame& f) { emit(describe_packet_json(t_s, PacketDirection::from_robot, f)); });
    } else if (record.kind == capture::RecordKind::tx) {
      tx_parser.feed(record.payload, record.t_ns,
                     [&](const Frame& f) { emit(describe_packet_json(t_s, PacketDirection::to_robot, f)); });
    } else if (record.kind == capture::RecordKind::baud_change) {
      std::string line;
      json::StringSink sink(line);
      json::Writer(sink).begin_object().key("t_s").fixed_or_null(t_s, 6).member_uint32("baud", record.baud).end_object();
      emit(line);
    }
  }
  std::string summary;
  const ParserStats& rx = rx_parser.stats();
  const ParserStats& tx = tx_parser.stats();
  json::StringSink sink(summary);
  json::Writer(sink)
      .begin_object()
      .member_bool("summary", true)
      .member_uint64("rx_packets", rx.frames)
      .member_uint64("tx_packets", tx.frames)
      .member_uint64("rx_bad_checksums", rx.bad_checksums)
      .member_uint64("tx_bad_checksums", tx.bad_checksums)
      .member_uint64("rx_discarded_bytes", rx.discarded_bytes)
      .member_uint64("tx_discarded_bytes", tx.discarded_bytes)
      .end_object();
  emit(summary);
  return Status::success();
}

}  // namespace sen3bot::p2os
