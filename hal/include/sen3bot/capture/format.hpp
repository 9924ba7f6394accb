#pragma once
// Wire capture files (.s3bcap), format version 1. All integers little-endian.
// The authoritative byte-by-byte description is docs/capture-format.md; the constants and
// the little-endian helpers below are the only place the code spells the layout.
//
//   file header      32 bytes   magic "S3BCAP\r\n", version, channel count, flags,
//                               start wall-clock ns (for humans), start monotonic ns
//   channel decl      8 + name  id, name length, reserved, baud at capture start, name
//   record           16 + len   t_ns since start, channel, kind, reserved, payload length,
//                               payload (rx/tx bytes, or a baud / gap / end payload)
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::capture {

// "S3BCAP" then CR LF: a text-mode copy or an FTP ASCII transfer breaks the magic at once.
inline constexpr std::array<std::uint8_t, 8> kMagic = {0x53, 0x33, 0x42, 0x43, 0x41, 0x50, 0x0D, 0x0A};
inline constexpr std::uint16_t kFormatVersion = 1;

inline constexpr std::size_t kFileHeaderBytes = 32;
inline constexpr std::size_t kChannelDeclBytes = 8;   // before the name bytes
inline constexpr std::size_t kRecordHeaderBytes = 16;  // before the payload bytes

// Bounds that keep a hostile file from steering allocation or loops.
inline constexpr std::size_t kMaxPayloadBytes = 64 * 1024;
inline constexpr std::size_t kMaxChannels = 32;
inline constexpr std::size_t kMaxChannelNameBytes = 32;
inline constexpr std::size_t kMaxFileBytes = std::size_t{1} << 30;  // load() refuses larger files

// Channel id used by records that belong to no channel (gap, end). Never declarable.
inline constexpr std::uint8_t kNoChannel = 0xFF;

// Payload sizes of the non-data record kinds.
inline constexpr std::size_t kBaudPayloadBytes = 4;  // u32 new baud
inline constexpr std::size_t kGapPayloadBytes = 16;  // u64 records dropped, u64 payload bytes dropped
inline constexpr std::size_t kEndPayloadBytes = 16;  // u64 records written, u64 records dropped

enum class Direction : std::uint8_t {
  rx = 0,  // device -> firmware
  tx = 1,  // firmware -> device
};

enum class RecordKind : std::uint8_t {
  rx = 0,           // bytes read from the device
  tx = 1,           // bytes the device accepted from the firmware
  baud_change = 2,  // the link switched baud rate at this time
  gap = 3,          // records were dropped here because the writer's buffer was full
  end = 4,          // clean close; always the last record
};
inline constexpr std::uint8_t kMaxRecordKind = 4;

std::string_view to_string(RecordKind kind) noexcept;
std::string_view to_string(Direction direction) noexcept;

struct ChannelDecl {
  std::uint8_t id = 0;      // 0..254
  std::string name;         // "p2os", "lms200": 1..32 printable ASCII characters, no spaces
  std::uint32_t baud = 0;   // baud rate when the capture started; 0 = unknown or not serial
};

// Everything before the first record.
struct CaptureInfo {
  std::int64_t start_wall_ns = 0;       // Unix time of the start, for humans only; 0 = unknown
  hal::Nanos start_monotonic_ns = 0;    // monotonic-clock reading that record time 0 maps to
  std::vector<ChannelDecl> channels;
};

// True if `name` is 1..kMaxChannelNameBytes bytes of 0x21..0x7E.
bool valid_channel_name(std::string_view name) noexcept;

// Little-endian field access; callers guarantee the span is long enough.
namespace le {
inline void put_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void put_u64(std::uint8_t* p, std::uint64_t v) noexcept {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void put_i64(std::uint8_t* p, std::int64_t v) noexcept { put_u64(p, static_cast<std::uint64_t>(v)); }
inline std::uint16_t get_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t get_u32(const std::uint8_t* p) noexcept {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
inline std::uint64_t get_u64(const std::uint8_t* p) noexcept {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
inline std::int64_t get_i64(const std::uint8_t* p) noexcept { return static_cast<std::int64_t>(get_u64(p)); }
}  // namespace le

// Header encoders shared by the writer and by tests that build files by hand.
std::array<std::uint8_t, kFileHeaderBytes> encode_file_header(const CaptureInfo& info) noexcept;
// Appends one channel declaration (8 bytes + name) to `out`.
void append_channel_decl(std::vector<std::uint8_t>& out, const ChannelDecl& channel);
std::array<std::uint8_t, kRecordHeaderBytes> encode_record_header(hal::Nanos t_ns, std::uint8_t channel,
                                                                  RecordKind kind,
                                                                  std::uint32_t payload_bytes) noexcept;

}  // namespace sen3bot::capture
