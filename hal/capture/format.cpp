#include "sen3bot/capture/format.hpp"

namespace sen3bot::capture {

std::string_view to_string(RecordKind kind) noexcept {
  switch (kind) {
    case RecordKind::rx: return "rx";
    case RecordKind::tx: return "tx";
    case RecordKind::baud_change: return "baud";
    case RecordKind::gap: return "gap";
    case RecordKind::end: return "end";
  }
  return "?";
}

std::string_view to_string(Direction direction) noexcept {
  return direction == Direction::rx ? "rx" : "tx";
}

bool valid_channel_name(std::string_view name) noexcept {
  if (name.empty() || name.size() > kMaxChannelNameBytes) return false;
  for (const char c : name) {
    if (c < 0x21 || c > 0x7E) return false;
  }
  return true;
}

std::array<std::uint8_t, kFileHeaderBytes> encode_file_header(const CaptureInfo& info) noexcept {
  std::array<std::uint8_t, kFileHeaderBytes> h{};
  for (std::size_t i = 0; i < kMagic.size(); ++i) h[i] = kMagic[i];
  le::put_u16(&h[8], kFormatVersion);
  le::put_u16(&h[10], static_cast<std::uint16_t>(info.channels.size()));
  le::put_u32(&h[12], 0);  // flags: none defined in version 1
  le::put_i64(&h[16], info.start_wall_ns);
  le::put_i64(&h[24], info.start_monotonic_ns);
  return h;
}

void append_channel_decl(std::vector<std::uint8_t>& out, const ChannelDecl& channel) {
  std::uint8_t d[kChannelDeclBytes] = {};
  d[0] = channel.id;
  d[1] = static_cast<std::uint8_t>(channel.name.size());
  le::put_u16(&d[2], 0);  // reserved
  le::put_u32(&d[4], channel.baud);
  out.insert(out.end(), d, d + kChannelDeclBytes);
  out.insert(out.end(), channel.name.begin(), channel.name.end());
}

std::array<std::uint8_t, kRecordHeaderBytes> encode_record_header(hal::Nanos t_ns, std::uint8_t channel,
                                                                  RecordKind kind,
                                                                  std::uint32_t payload_bytes) noexcept {
  std::array<std::uint8_t, kRecordHeaderBytes> h{};
  le::put_i64(&h[0], t_ns);
  h[8] = channel;
  h[9] = static_cast<std::uint8_t>(kind);
  le::put_u16(&h[10], 0);  // reserved
  le::put_u32(&h[12], payload_bytes);
  return h;
}

}  // namespace sen3bot::capture
