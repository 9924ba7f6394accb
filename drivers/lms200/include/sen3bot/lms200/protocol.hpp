#pragma once
// SICK LMS200 serial telegrams: layout, CRC, request builders and reply decoders.
// Pure code: no I/O, no clock, no allocation.
//
// Telegram (all multi-byte fields little-endian, no ETX):
//
//   offset  size      field
//   0       1         STX 0x02
//   1       1         ADR host->LMS: 0x00 (LMS address 0); LMS->host: 0x80 | LMS address
//   2       2         LEN u16: host: CMD + parameters; LMS: CMD + data + status byte
//   4       1         CMD host: command code; LMS: reply code = command + 0x80
//   5       LEN-1     host: parameters                      | LMS: LEN-2 data bytes, then
//                                                           |      the status byte S
//   4+LEN   2         CRC u16 over bytes 0 .. 4+LEN-1, low byte first
//
// Outside telegrams the LMS sends a standalone ACK 0x06 (request accepted, before the reply)
// or NAK 0x15 (bad CRC; resend after >= 30 ms). Streamed B0 scans have no ACK in front.
// A logically refused command is answered with the reply telegram 0x92.
//
// B0 scan data (modes 0x24 continuous, 0x2A partial, request 0x30 01):
//
//   B0 | count u16 | N x value u16 | [scan index, telegram index] | S
//   count bits 0-9 N, bit 10 reserved, bits 11-12 partial-scan offset (x 0.25 deg),
//   bit 13 partial scan, bits 14-15 units (00 cm, 01 mm, 10 dm on some firmware).
//   The two index bytes are present only when availability bit 0x02 is set; a decoder
//   tells them apart by LEN (= 2N + 4, or 2N + 6 with indices).
//
// B6 mean values (mode 0x26, request 20 26 M with M = 2..250 scans averaged):
//
//   B6 | M u8 | count u16 | N x value u16 | [scan index, telegram index] | S
//   LEN = 2N + 5, or 2N + 7 with indices. The values carry no flag bits.
//
// B7 sub-range (mode 0x27, request 20 27 first u16 last u16; 1-based indices into the
// complete scan, first <= last <= angle / resolution + 1):
//
//   B7 | first u16 | last u16 | count u16 | N x value u16 | [scan index, telegram index] | S
//   N = last - first + 1; LEN = 2N + 8, or 2N + 10 with indices.
//
// Layouts as sicktoolbox (SickLMS2xx, Telegram Listing pages 61 and 63) reads them; that the
// count words of B6 and B7 carry the units in bits 14-15 as B0 does is our assumption.
//
// Value word per measuring mode (configuration byte 5):
//   00, 02     bits 0-12 distance; 0x2000 field A, 0x4000 field B, 0x8000 dazzle (00) / field C (02)
//   01         bits 0-12 distance; bits 13-15 reflector level 0-7
//   03, 04     bits 0-13 distance; 03: bits 14-15 reflector level; 04: 0x4000 field A, 0x8000 field B
//   05, 06     bits 0-14 distance; 0x8000 reflector (05) / field A (06)
//   0F, 3F     bits 0-15 distance (3F: reflectivity), no flags
// In a 13-bit mode every value >= 8183 is a code, not a distance (8191 not valid, 8190
// dazzling, 8189 operation overflow, 8187 signal-to-noise too small, 8186 error reading
// channel 1, 8183 value > maximum, others reserved). Wider modes use the same offsets from
// their own maximum (16383 / 32767 / 65535).
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::lms200 {

// --- framing -----------------------------------------------------------------------------
inline constexpr std::uint8_t kStx = 0x02;
inline constexpr std::uint8_t kAck = 0x06;
inline constexpr std::uint8_t kNak = 0x15;
inline constexpr std::uint8_t kHostAddress = 0x00;        // requests to LMS address 0
inline constexpr std::uint8_t kReplyAddressFlag = 0x80;   // replies carry 0x80 | LMS address
inline constexpr std::size_t kHeaderBytes = 4;            // STX, ADR, LEN
inline constexpr std::size_t kCrcBytes = 2;
inline constexpr std::size_t kFrameOverheadBytes = kHeaderBytes + kCrcBytes;
// The largest real telegram (401 values with real-time indices) has LEN 808 and 814 bytes;
// LEN above 814 is never a telegram, whatever the margin a firmware revision might use.
inline constexpr std::uint16_t kMinLen = 1;
inline constexpr std::uint16_t kMaxLen = 814;
inline constexpr std::size_t kMaxFrameBytes = kMaxLen + kFrameOverheadBytes;  // 820
inline constexpr std::uint8_t kReplyCodeOffset = 0x80;

// --- command and reply codes ---------------------------------------------------------------
enum class Command : std::uint8_t {
  mode_change = 0x20,
  request_data = 0x30,
  status = 0x31,
  errors = 0x32,
  type = 0x3A,
  variant = 0x3B,
  read_config = 0x74,
  write_config = 0x77,
};
inline constexpr std::uint8_t kReplyModeChange = 0xA0;
inline constexpr std::uint8_t kReplyScan = 0xB0;
inline constexpr std::uint8_t kReplyMeanScan = 0xB6;
inline constexpr std::uint8_t kReplySubrangeScan = 0xB7;
inline constexpr std::uint8_t kReplyStatus = 0xB1;
inline constexpr std::uint8_t kReplyErrors = 0xB2;
inline constexpr std::uint8_t kReplyType = 0xBA;
inline constexpr std::uint8_t kReplyVariant = 0xBB;
inline constexpr std::uint8_t kReplyReadConfig = 0xF4;
inline constexpr std::uint8_t kReplyWriteConfig = 0xF7;
inline constexpr std::uint8_t kReplyPowerOn = 0x90;
inline constexpr std::uint8_t kReplyReset = 0x91;
inline constexpr std::uint8_t kReplyRejected = 0x92;  // "incorrect command"
constexpr std::uint8_t reply_code(Command c) { return static_cast<std::uint8_t>(static_cast<std::uint8_t>(c) + kReplyCodeOffset); }

// Operating modes, the byte after 0x20.
enum class OperatingMode : std::uint8_t {
  installation = 0x00,  // setup; needs the 8-byte password
  diagnostic = 0x10,
  continuous_all = 0x24,  // stream B0 with every value
  monitoring = 0x25,      // data only on request (stops streaming)
  mean_values = 0x26,     // stream B6: the mean of every S consecutive scans
  subrange = 0x27,        // stream B7: values first..last of each complete scan
  partial_scans = 0x2A,   // stream each mirror revolution's 1 deg raster with its offset
  baud_38400 = 0x40,
  baud_19200 = 0x41,
  baud_9600 = 0x42,
  baud_500000 = 0x48,
};
inline constexpr std::string_view kDefaultPassword = "SICK_LMS";
inline constexpr std::size_t kPasswordBytes = 8;

// A0 result byte.
inline constexpr std::uint8_t kModeChangeOk = 0x00;
inline constexpr std::uint8_t kModeChangeBadPassword = 0x01;
inline constexpr std::uint8_t kModeChangeFault = 0x02;

// Status byte S of a unit in normal operation (strict clients require it).
inline constexpr std::uint8_t kStatusNormal = 0x10;
// Bits 0-2 of S: 0 OK, 1 info, 2 warning, 3 error, 4 fatal (third-party reading of the
// Telegram Listing, unverified on a unit).
enum class StatusLevel : std::uint8_t { ok = 0, info = 1, warning = 2, error = 3, fatal = 4, reserved = 5 };
StatusLevel status_level(std::uint8_t status) noexcept;
// The status byte `status` with its level bits set to `level`.
std::uint8_t with_status_level(std::uint8_t status, StatusLevel level) noexcept;
// B1 device status (status offset 9): 0 OK, anything else a fault.
inline constexpr std::uint8_t kDeviceStatusOk = 0x00;
inline constexpr std::uint8_t kDeviceStatusFault = 0x01;

// Rates the LMS200 supports and their mode-change codes.
inline constexpr std::array<std::uint32_t, 4> kSupportedBauds = {9600, 19200, 38400, 500000};
Result<OperatingMode> baud_mode(std::uint32_t baud) noexcept;
std::uint32_t baud_of_mode(OperatingMode mode) noexcept;  // 0 if not a baud mode
// B1 status block baud word: 0x8000 | (round(1e6 / baud) - 1).
std::uint16_t status_baud_word(std::uint32_t baud) noexcept;
std::uint32_t baud_of_status_word(std::uint16_t word) noexcept;  // 0 if unknown

// --- variants, units, measuring modes ------------------------------------------------------
struct Variant {
  std::uint16_t angle_deg = 180;            // 100 or 180
  std::uint16_t resolution_cdeg = 100;      // 25, 50 or 100 (1/100 degree)
  friend bool operator==(const Variant&, const Variant&) = default;
};
bool valid_variant(Variant v) noexcept;  // 180/1, 180/0.5, 100/1, 100/0.5, 100/0.25
std::uint16_t value_count(Variant v) noexcept;  // angle / resolution + 1
// Mirror revolutions per complete scan: 1 (1 deg), 2 (0.5 deg), 4 (0.25 deg); 75 Hz mirror.
inline constexpr std::int64_t kMirrorPeriodNs = 40'000'000 / 3;  // 1/75 s
std::int64_t scan_period_ns(Variant v) noexcept;

enum class Units : std::uint8_t { cm = 0, mm = 1, dm = 2 };
std::string_view to_string(Units u) noexcept;
double metres_per_unit(Units u) noexcept;

// Configuration byte 5.
enum class MeasuringMode : std::uint8_t {
  range8_fields_dazzle = 0x00,
  range8_reflector8 = 0x01,
  range8_fields_abc = 0x02,
  range16_reflector4 = 0x03,
  range16_fields_ab = 0x04,
  range32_reflector2 = 0x05,
  range32_field_a = 0x06,
  range32_immediate = 0x0F,
  reflectivity = 0x3F,
};
bool valid_measuring_mode(std::uint8_t mode) noexcept;

// How a measuring mode splits the value word.
struct ValueLayout {
  std::uint16_t distance_mask;  // 0x1FFF, 0x3FFF, 0x7FFF or 0xFFFF
  std::uint16_t first_code;     // distances >= this are codes (distance_mask - 8)
};
ValueLayout value_layout(MeasuringMode mode) noexcept;

// Why a value is not a distance.
enum class InvalidReason : std::uint8_t {
  none = 0,
  not_valid = 1,           // max
  dazzling = 2,            // max - 1
  operation_overflow = 3,  // max - 2
  snr_too_small = 4,       // max - 4
  channel1_error = 5,      // max - 5
  over_maximum = 6,        // max - 8
  reserved_code = 7,       // any other value >= max - 8
};
std::string_view to_string(InvalidReason r) noexcept;
InvalidReason classify(std::uint16_t distance, ValueLayout layout) noexcept;
// The raw distance that a code is sent as in a given layout (for emulators and tests).
std::uint16_t code_value(InvalidReason r, ValueLayout layout) noexcept;

// Per-value flags decoded from the high bits (ScanValue::flags).
namespace value_flag {
inline constexpr std::uint8_t kValid = 0x01;
inline constexpr std::uint8_t kFieldA = 0x02;
inline constexpr std::uint8_t kFieldB = 0x04;
inline constexpr std::uint8_t kFieldC = 0x08;
inline constexpr std::uint8_t kDazzle = 0x10;
inline constexpr std::uint8_t kReflectorShift = 5;  // bits 5-7: reflector level 0-7
}  // namespace value_flag
// Splits one value word: distance (masked), flags, invalid reason.
struct ScanValue {
  std::uint16_t distance = 0;
  std::uint8_t flags = 0;
  InvalidReason reason = InvalidReason::none;
};
ScanValue decode_value(std::uint16_t word, MeasuringMode mode) noexcept;
// Inverse, for emulators: distance (or code) plus the mode's flag bits.
std::uint16_t encode_value(std::uint16_t distance, std::uint8_t flags, MeasuringMode mode) noexcept;

// --- CRC -----------------------------------------------------------------------------------
// SICK's CRC-16: polynomial 0x8005, no reflection, no final XOR, each step mixes the
// previous byte into the high half of the data word.
std::uint16_t crc16(std::span<const std::uint8_t> bytes) noexcept;

// --- request builders ----------------------------------------------------------------------
// Largest request: 0x77 with a 34-byte block -> LEN 35, 41 bytes.
inline constexpr std::size_t kMaxRequestBytes = 48;
struct Request {
  std::array<std::uint8_t, kMaxRequestBytes> bytes{};
  std::uint8_t size = 0;
  [[nodiscard]] std::span<const std::uint8_t> span() const noexcept { return {bytes.data(), size}; }
  [[nodiscard]] std::uint8_t command() const noexcept { return bytes[4]; }
};
// Frames any payload (CMD + parameters) to LMS address `address`. Payload size 1..42.
Request make_request(std::span<const std::uint8_t> payload, std::uint8_t address = 0) noexcept;
Request request_mode(OperatingMode mode) noexcept;  // 20 mm, for every mode but installation
Request request_installation_mode(std::string_view password = kDefaultPassword) noexcept;  // 20 00 + 8 bytes
Request request_baud(std::uint32_t baud) noexcept;   // 20 40/41/42/48; baud must be supported
Request request_status() noexcept;                   // 31
Request request_errors() noexcept;                   // 32
Request request_type() noexcept;                     // 3A
Request request_variant(Variant v) noexcept;         // 3B angle res
Request request_read_config() noexcept;              // 74
Request request_write_config(std::span<const std::uint8_t> block) noexcept;  // 77 + 7..34 bytes
Request request_single_scan() noexcept;              // 30 01
// Scans averaged per B6 telegram (sicktoolbox refuses anything else).
inline constexpr std::uint8_t kMinMeanSamples = 2;
inline constexpr std::uint8_t kMaxMeanSamples = 250;
Result<Request> request_mean_values(std::uint8_t samples) noexcept;  // 20 26 S
// 20 27 first last; 1 <= first <= last <= value_count(variant).
Result<Request> request_subrange(std::uint16_t first, std::uint16_t last, Variant variant) noexcept;

// --- replies ---------------------------------------------------------------------------------
// A CRC-checked telegram as the parser delivers it; `bytes` is the whole frame.
struct FrameView {
  std::span<const std::uint8_t> bytes;
  [[nodiscard]] std::uint8_t address() const noexcept { return bytes[1]; }
  [[nodiscard]] std::uint16_t len() const noexcept {
    return static_cast<std::uint16_t>(bytes[2] | (bytes[3] << 8));
  }
  [[nodiscard]] std::uint8_t code() const noexcept { return bytes[4]; }
  // CMD + data (+ status for replies): LEN bytes.
  [[nodiscard]] std::span<const std::uint8_t> payload() const noexcept { return bytes.subspan(4, len()); }
  // Reply data between the code and the status byte.
  [[nodiscard]] std::span<const std::uint8_t> reply_data() const noexcept {
    return len() >= 2 ? bytes.subspan(5, len() - 2u) : std::span<const std::uint8_t>{};
  }
  [[nodiscard]] std::uint8_t reply_status() const noexcept { return bytes[4 + len() - 1]; }
};

// Frames a reply (code + data + status) from LMS address `address` into `out`
// (at least data.size() + 8 bytes). Returns the frame size.
std::size_t make_reply(std::uint8_t code, std::span<const std::uint8_t> data, std::uint8_t status,
                       std::span<std::uint8_t> out, std::uint8_t address = 0) noexcept;

struct ModeChangeReply {  // A0
  std::uint8_t result = 0;  // kModeChangeOk, ...
  std::uint8_t status = 0;
};
Result<ModeChangeReply> decode_mode_change(FrameView f) noexcept;

inline constexpr std::size_t kStatusDataBytes = 152;
struct StatusReply {  // B1
  std::array<char, 8> software_version{};  // 7 ASCII chars + NUL
  std::uint8_t operating_mode = 0;
  std::uint8_t device_status = 0;  // 0 OK
  std::uint8_t variant_type = 0;
  std::uint8_t measuring_mode = 0;
  Variant variant;
  std::uint32_t baud = 0;  // 0 if the word is unknown
  std::uint8_t permanent_baud = 0;
  std::uint8_t lms_address = 0;
  std::uint8_t units = 0;
  std::uint8_t status = 0;
};
// Data offsets inside B1 (index 0 is the B1 code itself, as in the public drivers).
namespace status_offset {
inline constexpr std::size_t kVersion = 1;
inline constexpr std::size_t kOperatingMode = 8;
inline constexpr std::size_t kDeviceStatus = 9;
inline constexpr std::size_t kVariantType = 18;
inline constexpr std::size_t kMeasuringMode = 102;
inline constexpr std::size_t kScanAngle = 107;
inline constexpr std::size_t kResolution = 109;
inline constexpr std::size_t kBaud = 116;
inline constexpr std::size_t kPermanentBaud = 119;
inline constexpr std::size_t kAddress = 120;
inline constexpr std::size_t kUnits = 122;
}  // namespace status_offset
Result<StatusReply> decode_status(FrameView f) noexcept;

struct TypeReply {  // BA
  std::array<char, 32> type{};  // NUL-terminated, truncated
  std::uint8_t status = 0;
};
Result<TypeReply> decode_type(FrameView f) noexcept;

struct VariantReply {  // BB
  bool accepted = false;
  Variant variant;
  std::uint8_t status = 0;
};
Result<VariantReply> decode_variant(FrameView f) noexcept;

// Configuration block of 0x74 / 0x77: 34 bytes (32 on older LMS200 firmware).
inline constexpr std::size_t kConfigBytes = 34;
inline constexpr std::size_t kConfigBytesShort = 32;
inline constexpr std::size_t kMinWriteConfigBytes = 7;
namespace config_offset {
inline constexpr std::size_t kBlanking = 0;
inline constexpr std::size_t kAvailability = 4;
inline constexpr std::size_t kMeasuringMode = 5;
inline constexpr std::size_t kUnits = 6;
}  // namespace config_offset
inline constexpr std::uint8_t kAvailabilityRealTimeIndices = 0x02;
struct ConfigBlock {
  std::array<std::uint8_t, kConfigBytes> bytes{};
  std::uint8_t size = 0;  // 32 or 34
  [[nodiscard]] std::span<const std::uint8_t> span() const noexcept { return {bytes.data(), size}; }
  [[nodiscard]] std::uint8_t measuring_mode() const noexcept { return bytes[config_offset::kMeasuringMode]; }
  [[nodiscard]] std::uint8_t units() const noexcept { return bytes[config_offset::kUnits]; }
  [[nodiscard]] std::uint8_t availability() const noexcept { return bytes[config_offset::kAvailability]; }
};
struct ConfigReply {  // F4, or F7 with its accepted flag
  bool accepted = true;
  ConfigBlock block;
  std::uint8_t status = 0;
};
Result<ConfigReply> decode_read_config(FrameView f) noexcept;
Result<ConfigReply> decode_write_config(FrameView f) noexcept;

inline constexpr std::size_t kMaxValues = 401;
struct ScanTelegram {  // B0, B6 or B7
  std::uint8_t code = kReplyScan;
  std::uint8_t mean_samples = 0;  // B6: scans averaged; 0 for B0 and B7
  std::uint16_t first_index = 1;  // 1-based position of words[0] in the complete scan (B7: first)
  std::uint16_t last_index = 0;   // B7: last; B0 and B6: count
  std::uint16_t count = 0;
  Units units = Units::cm;
  bool partial = false;
  std::uint8_t partial_offset_qdeg = 0;  // 0..3 x 0.25 deg
  bool has_indices = false;
  std::uint8_t scan_index = 0;
  std::uint8_t telegram_index = 0;
  std::uint8_t status = 0;
  std::array<std::uint16_t, kMaxValues> words{};  // raw value words
};
Result<ScanTelegram> decode_scan(FrameView f) noexcept;           // B0 only
Result<ScanTelegram> decode_mean_scan(FrameView f) noexcept;      // B6 only
Result<ScanTelegram> decode_subrange_scan(FrameView f) noexcept;  // B7 only
Result<ScanTelegram> decode_any_scan(FrameView f) noexcept;       // B0, B6 or B7 by its code

// The reply code that answers `request_code`, as a check for correlation.
constexpr bool answers(std::uint8_t reply, std::uint8_t request_code) {
  return reply == static_cast<std::uint8_t>(request_code + kReplyCodeOffset);
}

}  // namespace sen3bot::lms200
