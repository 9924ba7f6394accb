#include "sen3bot/p2os/describe.hpp"

#include <cstdio>
#include <string_view>

namespace sen3bot::p2os {

namespace {

void append(std::string& out, const char* fmt, auto... args) {
  char text[160];
  const int n = std::snprintf(text, sizeof text, fmt, args...);
  if (n > 0) out.append(text, static_cast<std::size_t>(n) < sizeof text ? static_cast<std::size_t>(n) : sizeof text - 1);
}

void append_string(std::string& out, std::string_view key, const char* value, std::size_t capacity) {
  out += ",\"";
  out += key;
  out += "\":\"";
  for (std::size_t i = 0; i < capacity && value[i] != '\0'; ++i) {
    const auto c = static_cast<unsigned char>(value[i]);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c >= 0x7F) {
      append(out, "\\u%04x", static_cast<unsigned>(c));
    } else {
      out += static_cast<char>(c);
    }
  }
  out += '"';
}

void describe_command(std::string& out, const Frame& frame) {
  append(out, ",\"type\":\"%s\",\"cmd\":%u", std::string(command_name(frame.type)).c_str(),
         static_cast<unsigned>(frame.type));
  const CommandArgument arg = decode_argument(frame.payload);
  if (arg.kind == ArgKind::integer) {
    append(out, ",\"arg\":%d", arg.value);
    if (frame.type == static_cast<std::uint8_t>(Command::vel2)) {
      const Vel2Units units = decode_vel2(arg);
      append(out, ",\"left\":%d,\"right\":%d", units.left, units.right);
    }
  } else if (arg.kind == ArgKind::string) {
    out += ",\"text\":\"";
    for (const std::uint8_t b : arg.text) append(out, "%02x", static_cast<unsigned>(b));
    out += '"';
  }
}

void describe_server(std::string& out, const Frame& frame) {
  append(out, ",\"type\":\"%s\",\"code\":%u", std::string(server_type_name(frame.type)).c_str(),
         static_cast<unsigned>(frame.type));
  if (auto sip = decode_sip(frame)) {
    append(out, ",\"moving\":%s,\"x\":%u,\"y\":%u,\"th\":%d,\"lvel\":%d,\"rvel\":%d", sip->moving ? "true" : "false",
           static_cast<unsigned>(sip->x_raw), static_cast<unsigned>(sip->y_raw), sip->theta_raw, sip->left_vel_mm_s,
           sip->right_vel_mm_s);
    append(out, ",\"battery_dv\":%u,\"stallbump\":%u,\"control\":%d,\"flags\":%u,\"compass\":%u,\"sonar\":%u",
           static_cast<unsigned>(sip->battery_dv), static_cast<unsigned>(sip->stall_bumpers), sip->control_raw,
           static_cast<unsigned>(sip->flags), static_cast<unsigned>(sip->compass_2deg),
           static_cast<unsigned>(sip->sonar_count));
    if (sip->has_rot_vel) append(out, ",\"rotvel_ddeg_s\":%d", sip->rot_vel_ddeg_s);
    if (sip->has_battery_x10) append(out, ",\"battery_x10\":%u", static_cast<unsigned>(sip->battery_x10));
    return;
  }
  if (auto reply = decode_sync2_reply(frame)) {
    append_string(out, "name", reply->name.data(), reply->name.size());
    append_string(out, "class", reply->robot_class.data(), reply->robot_class.size());
    append_string(out, "subclass", reply->subclass.data(), reply->subclass.size());
    return;
  }
  if (auto config = decode_config(frame)) {
    append_string(out, "class", config->robot_class.data(), config->robot_class.size());
    append_string(out, "subclass", config->subclass.data(), config->subclass.size());
    append_string(out, "serial", config->serial.data(), config->serial.size());
    append_string(out, "name", config->name.data(), config->name.size());
    append(out, ",\"sip_cycle_ms\":%u,\"watchdog_ms\":%u,\"auto_baud\":%u,\"trans_vel_max\":%u,\"rot_vel_max\":%u",
           static_cast<unsigned>(config->sip_cycle_ms), static_cast<unsigned>(config->watchdog_ms),
           static_cast<unsigned>(config->auto_baud), static_cast<unsigned>(config->trans_vel_max_mm_s),
           static_cast<unsigned>(config->rot_vel_max_deg_s));
    return;
  }
  if (auto enc = decode_encoder(frame)) {
    append(out, ",\"left_ticks\":%d,\"right_ticks\":%d", enc->left_ticks, enc->right_ticks);
    return;
  }
  if (frame.type == kTypeSipStopped || frame.type == kTypeSipMoving) out += ",\"malformed\":true";
}

}  // namespace

std::string describe_packet_json(double t_s, PacketDirection direction, const Frame& frame) {
  std::string out;
  out.reserve(256);
  append(out, "{\"t_s\":%.6f,\"dir\":\"%s\"", t_s, direction == PacketDirection::to_robot ? "tx" : "rx");
  if (direction == PacketDirection::to_robot) {
    describe_command(out, frame);
  } else {
    describe_server(out, frame);
  }
  append(out, ",\"bytes\":%zu}", frame.raw.size());
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
      append(line, "{\"t_s\":%.6f,\"baud\":%u}", t_s, static_cast<unsigned>(record.baud));
      emit(line);
    }
  }
  std::string summary;
  const ParserStats& rx = rx_parser.stats();
  const ParserStats& tx = tx_parser.stats();
  append(summary, "{\"summary\":true,\"rx_packets\":%llu,\"tx_packets\":%llu,\"rx_bad_checksums\":%llu,",
         static_cast<unsigned long long>(rx.frames), static_cast<unsigned long long>(tx.frames),
         static_cast<unsigned long long>(rx.bad_checksums));
  append(summary, "\"tx_bad_checksums\":%llu,\"rx_discarded_bytes\":%llu,\"tx_discarded_bytes\":%llu}",
         static_cast<unsigned long long>(tx.bad_checksums), static_cast<unsigned long long>(rx.discarded_bytes),
         static_cast<unsigned long long>(tx.discarded_bytes));
  emit(summary);
  return Status::success();
}

}  // namespace sen3bot::p2os
