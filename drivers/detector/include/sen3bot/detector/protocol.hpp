#pragma once
// The remote person detector's message (docs/people.md, "The detection datagram"): one UDP
// datagram per camera frame with the person boxes found in it. Version 1, little-endian:
//
//   offset  size  field
//   0       4     magic "S3PD"
//   4       1     version (1)
//   5       1     flags (0; anything else is refused)
//   6       2     count: boxes that follow (0..16)
//   8       4     source: the detector's id
//   12      4     sequence: the detector's frame counter, +1 per datagram
//   16      8     capture time of the frame, Unix ns (the detector's clock, NTP-synchronised)
//   24      2     image width, px
//   26      2     image height, px
//   28      12    per box: u0, v0, u1, v1 (px, uint16), confidence (uint16, 1/10000), class (uint16)
//   28+12n  4     CRC-32 (IEEE 802.3) of every byte before it
//
// decode() is the codec; DetectionGate checks a decoded datagram against the camera and the
// clocks, and counts each refusal by its reason.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/detector/detections.hpp"

namespace sen3bot::detector {

inline constexpr std::uint8_t kVersion = 1;
inline constexpr std::size_t kHeaderBytes = 28;
inline constexpr std::size_t kBoxBytes = 12;
inline constexpr std::size_t kCrcBytes = 4;
inline constexpr std::size_t kMaxBoxes = Detections::kMax;
inline constexpr std::size_t kMaxDatagramBytes = kHeaderBytes + kMaxBoxes * kBoxBytes + kCrcBytes;

struct Datagram {
  std::uint32_t source = 0;
  std::uint32_t sequence = 0;
  std::int64_t capture_unix_ns = 0;
  std::uint16_t width_px = 0;
  std::uint16_t height_px = 0;
  std::uint8_t count = 0;
  std::array<Box, kMaxBoxes> boxes{};
};

// Why a datagram was refused.
enum class Reject : std::uint8_t {
  too_short,       // shorter than a header and a CRC
  too_long,        // longer than 16 boxes
  bad_magic,
  bad_version,     // another version, or flags set
  bad_length,      // the count does not match the length
  bad_crc,
  bad_box,         // u0 >= u1, v0 >= v1, a corner outside the image, confidence above 1
  wrong_image,     // not the configured camera's image size
  stale,           // captured longer ago than max_age_s
  future,          // captured later than now by more than max_future_s
  replayed,        // a sequence number seen already from that source
  too_many_sources,
};
inline constexpr std::size_t kRejects = 12;
[[nodiscard]] const char* to_string(Reject reason) noexcept;

[[nodiscard]] std::uint32_t crc32(std::span<const std::uint8_t> bytes) noexcept;

// The wire bytes of d (boxes rounded to whole pixels and 1/10000); 0 when out is too small or
// d.count > 16.
std::size_t encode(const Datagram& d, std::span<std::uint8_t> out) noexcept;
// Checks the framing (length, magic, version, CRC) and each box against the datagram's own
// image size; true when d holds it, else `why` says why.
bool decode(std::span<const std::uint8_t> bytes, Datagram& d, Reject& why) noexcept;

struct GateConfig {
  std::uint16_t width_px = 1280;  // the camera's image
  std::uint16_t height_px = 720;
  double max_age_s = 0.5;
  double max_future_s = 0.05;
};

// The receiving side: decode, then the camera, the clocks and replays. Fixed memory.
class DetectionGate {
 public:
  static constexpr std::size_t kMaxSources = 4;
  explicit DetectionGate(const GateConfig& config = {}) noexcept : config_(config) {}

  // now_ns on the firmware's clock, now_unix_ns the wall clock at the same moment; the frame's
  // capture time comes out on the firmware's clock. False when refused (counted).
  bool accept(std::span<const std::uint8_t> bytes, hal::Nanos now_ns, std::int64_t now_unix_ns,
              Detections& out) noexcept;
  [[nodiscard]] std::uint64_t rejected(Reject reason) const noexcept { return rejected_[static_cast<std::size_t>(reason)]; }
  [[nodiscard]] std::uint64_t accepted() const noexcept { return accepted_; }

 private:
  struct Source {
    std::uint32_t id = 0;
    std::uint32_t last_sequence = 0;
    std::int64_t last_capture_unix_ns = 0;
  };
  bool refuse(Reject reason) noexcept;

  GateConfig config_;
  std::array<Source, kMaxSources> sources_{};
  std::size_t source_count_ = 0;
  std::array<std::uint64_t, kRejects> rejected_{};
  std::uint64_t accepted_ = 0;
};

}  // namespace sen3bot::detector
