#include "sen3bot/detector/protocol.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::detector {

namespace {

constexpr std::uint8_t kMagic[4] = {'S', '3', 'P', 'D'};

constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table();

std::uint16_t get16(const std::uint8_t* p) noexcept { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint32_t get32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint64_t get64(const std::uint8_t* p) noexcept {
  return static_cast<std::uint64_t>(get32(p)) | (static_cast<std::uint64_t>(get32(p + 4)) << 32);
}
void put16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put64(std::uint8_t* p, std::uint64_t v) noexcept {
  put32(p, static_cast<std::uint32_t>(v));
  put32(p + 4, static_cast<std::uint32_t>(v >> 32));
}
std::uint16_t pixel(float v) noexcept {
  if (!(v > 0.0f)) return 0;
  return v >= 65535.0f ? std::uint16_t{65535} : static_cast<std::uint16_t>(std::lround(v));
}

}  // namespace

const char* to_string(Reject reason) noexcept {
  switch (reason) {
    case Reject::too_short: return "too_short";
    case Reject::too_long: return "too_long";
    case Reject::bad_magic: return "bad_magic";
    case Reject::bad_version: return "bad_version";
    case Reject::bad_length: return "bad_length";
    case Reject::bad_crc: return "bad_crc";
    case Reject::bad_box: return "bad_box";
    case Reject::wrong_image: return "wrong_image";
    case Reject::stale: return "stale";
    case Reject::future: return "future";
    case Reject::replayed: return "replayed";
    case Reject::too_many_sources: return "too_many_sources";
  }
  return "unknown";
}

std::uint32_t crc32(std::span<const std::uint8_t> bytes) noexcept {
  std::uint32_t c = 0xFFFFFFFFu;
  for (const std::uint8_t b : bytes) c = kCrcTable[(c ^ b) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::size_t encode(const Datagram& d, std::span<std::uint8_t> out) noexcept {
  if (d.count > kMaxBoxes) return 0;
  const std::size_t size = kHeaderBytes + d.count * kBoxBytes + kCrcBytes;
  if (out.size() < size) return 0;
  std::uint8_t* p = out.data();
  for (int i = 0; i < 4; ++i) p[i] = kMagic[i];
  p[4] = kVersion;
  p[5] = 0;
  put16(p + 6, d.count);
  put32(p + 8, d.source);
  put32(p + 12, d.sequence);
  put64(p + 16, static_cast<std::uint64_t>(d.capture_unix_ns));
  put16(p + 24, d.width_px);
  put16(p + 26, d.height_px);
  for (std::size_t b = 0; b < d.count; ++b) {
    std::uint8_t* q = p + kHeaderBytes + b * kBoxBytes;
    const Box& box = d.boxes[b];
    put16(q, pixel(box.u0));
    put16(q + 2, pixel(box.v0));
    put16(q + 4, pixel(box.u1));
    put16(q + 6, pixel(box.v1));
    put16(q + 8, static_cast<std::uint16_t>(std::lround(std::clamp(box.confidence, 0.0f, 1.0f) * 10000.0f)));
    put16(q + 10, box.class_id);
  }
  put32(p + size - kCrcBytes, crc32(out.first(size - kCrcBytes)));
  return size;
}

bool decode(std::span<const std::uint8_t> bytes, Datagram& d, Reject& why) noexcept {
  if (bytes.size() < kHeaderBytes + kCrcBytes) {
    why = Reject::too_short;
    return false;
  }
  if (bytes.size() > kMaxDatagramBytes) {
    why = Reject::too_long;
    return false;
  }
  const std::uint8_t* p = bytes.data();
  if (p[0] != kMagic[0] || p[1] != kMagic[1] || p[2] != kMagic[2] || p[3] != kMagic[3]) {
    why = Reject::bad_magic;
    return false;
  }
  if (p[4] != kVersion || p[5] != 0) {
    why = Reject::bad_version;
    return false;
  }
  const std::uint16_t count = get16(p + 6);
  if (count > kMaxBoxes || bytes.size() != kHeaderBytes + count * kBoxBytes + kCrcBytes) {
    why = Reject::bad_length;
    return false;
  }
  if (get32(p + bytes.size() - kCrcBytes) != crc32(bytes.first(bytes.size() - kCrcBytes))) {
    why = Reject::bad_crc;
    return false;
  }
  d.count = static_cast<std::uint8_t>(count);
  d.source = get32(p + 8);
  d.sequence = get32(p + 12);
  d.capture_unix_ns = static_cast<std::int64_t>(get64(p + 16));
  d.width_px = get16(p + 24);
  d.height_px = get16(p + 26);
  for (std::size_t b = 0; b < count; ++b) {
    const std::uint8_t* q = p + kHeaderBytes + b * kBoxBytes;
    const std::uint16_t u0 = get16(q), v0 = get16(q + 2), u1 = get16(q + 4), v1 = get16(q + 6);
    const std::uint16_t confidence = get16(q + 8);
    if (u0 >= u1 || v0 >= v1 || u1 > d.width_px || v1 > d.height_px || confidence > 10000) {
      why = Reject::bad_box;
      return false;
    }
    d.boxes[b] = {static_cast<float>(u0), static_cast<float>(v0), static_cast<float>(u1), static_cast<float>(v1),
                  static_cast<float>(confidence) / 10000.0f, get16(q + 10)};
  }
  return true;
}

bool DetectionGate::refuse(Reject reason) noexcept {
  ++rejected_[static_cast<std::size_t>(reason)];
  return false;
}

bool DetectionGate::accept(std::span<const std::uint8_t> bytes, hal::Nanos now_ns, std::int64_t now_unix_ns,
                           Detections& out) noexcept {
  Datagram d;
  Reject why = Reject::too_short;
  if (!decode(bytes, d, why)) return refuse(why);
  if (d.width_px != config_.width_px || d.height_px != config_.height_px) return refuse(Reject::wrong_image);
  // In doubles: a hostile capture time must not overflow the subtraction.
  const double age_s = (static_cast<double>(now_unix_ns) - static_cast<double>(d.capture_unix_ns)) * 1e-9;
  if (age_s > config_.max_age_s) return refuse(Reject::stale);
  if (-age_s > config_.max_future_s) return refuse(Reject::future);
  Source* source = nullptr;
  for (std::size_t i = 0; i < source_count_; ++i)
    if (sources_[i].id == d.source) source = &sources_[i];
  if (source == nullptr) {
    if (source_count_ == sources_.size()) return refuse(Reject::too_many_sources);
    source = &sources_[source_count_++];
    *source = {d.source, d.sequence, d.capture_unix_ns};
  } else {
    // Sequence numbers only grow (modulo 2^32). A smaller or equal one is a replay, unless its
    // frame is newer than the last by more than max_age_s: the detector restarted.
    const bool newer = static_cast<std::int32_t>(d.sequence - source->last_sequence) > 0;
    const bool restarted = static_cast<double>(d.capture_unix_ns - source->last_capture_unix_ns) * 1e-9 > config_.max_age_s;
    if (!newer && !restarted) return refuse(Reject::replayed);
    source->last_sequence = d.sequence;
    source->last_capture_unix_ns = d.capture_unix_ns;
  }
  out.count = d.count;
  for (std::size_t b = 0; b < d.count; ++b) out.boxes[b] = d.boxes[b];
  out.source = d.source;
  out.sequence = d.sequence;
  out.capture_ns = now_ns - (now_unix_ns - d.capture_unix_ns);
  ++accepted_;
  return true;
}

}  // namespace sen3bot::detector
