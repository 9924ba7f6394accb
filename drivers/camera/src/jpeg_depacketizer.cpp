#include <algorithm>
#include <cstring>

#include "sen3bot/camera/depacketizer.hpp"

namespace sen3bot::camera {
namespace {

// JPEG Annex K.1 / K.2 quantization tables, natural (row-major) order.
constexpr std::uint8_t kLumaQuant[64] = {
    16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
    14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
    18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
constexpr std::uint8_t kChromaQuant[64] = {
    17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99, 24, 26, 56, 99, 99, 99,
    99, 99, 47, 66, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
    99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99};
// Natural-order index of the i-th coefficient in zig-zag order (JPEG figure A.6).
constexpr std::uint8_t kZigzag[64] = {
    0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,  12, 19, 26, 33, 40, 48,
    41, 34, 27, 20, 13, 6,  7,  14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23,
    30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

// JPEG Annex K.3 standard Huffman tables: 16 code-length counts, then the symbols.
constexpr std::uint8_t kDcLumaBits[16] = {0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0};
constexpr std::uint8_t kDcChromaBits[16] = {0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0};
constexpr std::uint8_t kDcSymbols[12] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
constexpr std::uint8_t kAcLumaBits[16] = {0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 0x7d};
constexpr std::uint8_t kAcLumaSymbols[162] = {
    0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61, 0x07, 0x22, 0x71,
    0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52, 0xd1, 0xf0, 0x24, 0x33, 0x62, 0x72,
    0x82, 0x09, 0x0a, 0x16, 0x17, 0x18, 0x19, 0x1a, 0x25, 0x26, 0x27, 0x28, 0x29, 0x2a, 0x34, 0x35, 0x36, 0x37,
    0x38, 0x39, 0x3a, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59,
    0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68, 0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x83,
    0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9a, 0xa2, 0xa3,
    0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3,
    0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe1, 0xe2,
    0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf1, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa};
constexpr std::uint8_t kAcChromaBits[16] = {0, 2, 1, 2, 4, 4, 3, 4, 7, 5, 4, 4, 0, 1, 2, 0x77};
constexpr std::uint8_t kAcChromaSymbols[162] = {
    0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61, 0x71, 0x13, 0x22,
    0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xa1, 0xb1, 0xc1, 0x09, 0x23, 0x33, 0x52, 0xf0, 0x15, 0x62, 0x72, 0xd1,
    0x0a, 0x16, 0x24, 0x34, 0xe1, 0x25, 0xf1, 0x17, 0x18, 0x19, 0x1a, 0x26, 0x27, 0x28, 0x29, 0x2a, 0x35, 0x36,
    0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58,
    0x59, 0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68, 0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a,
    0x82, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9a,
    0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba,
    0xc2, 0xc3, 0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda,
    0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa};

constexpr std::size_t kMainHeaderBytes = 8;     // RFC 2435 §3.1
constexpr std::size_t kRestartHeaderBytes = 4;  // §3.1.7
constexpr std::size_t kQuantHeaderBytes = 4;    // §3.1.8
constexpr std::size_t kMaxJfifHeaderBytes = 1024;

class Writer {
 public:
  explicit Writer(std::uint8_t* p) : p_(p) {}
  void u8(std::uint8_t v) { p_[n_++] = v; }
  void u16(std::size_t v) {
    u8(static_cast<std::uint8_t>(v >> 8));
    u8(static_cast<std::uint8_t>(v));
  }
  void bytes(const std::uint8_t* d, std::size_t len) {
    std::memcpy(p_ + n_, d, len);
    n_ += len;
  }
  void dht(std::uint8_t class_id, const std::uint8_t* bits, const std::uint8_t* symbols, std::size_t count) {
    u8(0xFF);
    u8(0xC4);
    u16(2 + 1 + 16 + count);
    u8(class_id);
    bytes(bits, 16);
    bytes(symbols, count);
  }
  [[nodiscard]] std::size_t size() const { return n_; }

 private:
  std::uint8_t* p_;
  std::size_t n_ = 0;
};

}  // namespace

void make_jpeg_quant_tables(int q, std::span<std::uint8_t, 128> out) {
  q = std::clamp(q, 1, 99);
  const int scale = q < 50 ? 5000 / q : 200 - 2 * q;
  for (int i = 0; i < 64; ++i) {
    const int luma = (kLumaQuant[kZigzag[i]] * scale + 50) / 100;
    const int chroma = (kChromaQuant[kZigzag[i]] * scale + 50) / 100;
    out[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(std::clamp(luma, 1, 255));
    out[static_cast<std::size_t>(64 + i)] = static_cast<std::uint8_t>(std::clamp(chroma, 1, 255));
  }
}

JpegDepacketizer::JpegDepacketizer(std::size_t max_frame_bytes)
    : frame_(max_frame_bytes + kMaxJfifHeaderBytes + 2), max_scan_bytes_(max_frame_bytes) {}

void JpegDepacketizer::reset() { discard_frame(); }

void JpegDepacketizer::discard_frame() {
  open_ = false;
  frame_size_ = 0;
  header_size_ = 0;
  next_offset_ = 0;
}

// Parses the RFC 2435 headers of a frame's first packet and writes the JFIF header.
bool JpegDepacketizer::start_frame(std::span<const std::uint8_t> p, std::size_t& scan_offset) {
  const std::uint8_t type = p[4];
  const std::uint8_t q = p[5];
  int width = p[6] * 8;
  int height = p[7] * 8;
  if (width == 0) width = fallback_width_px_;
  if (height == 0) height = fallback_height_px_;
  std::size_t pos = kMainHeaderBytes;
  std::uint16_t restart_interval = 0;
  const std::uint8_t base_type = type >= 64 && type < 128 ? static_cast<std::uint8_t>(type - 64) : type;
  if (base_type > 1 || type >= 128) {
    ++stats_.unsupported_packets;
    return false;
  }
  if (type >= 64) {
    if (p.size() < pos + kRestartHeaderBytes) {
      ++stats_.malformed_packets;
      return false;
    }
    restart_interval = static_cast<std::uint16_t>((p[pos] << 8) | p[pos + 1]);
    pos += kRestartHeaderBytes;
  }
  if (width <= 0 || height <= 0) {
    ++stats_.malformed_packets;
    return false;
  }
  std::uint8_t tables[128];
  std::size_t table_bytes = 128;
  if (q >= 100 && q < 128) {
    ++stats_.unsupported_packets;  // reserved
    return false;
  }
  if (q < 100) {
    make_jpeg_quant_tables(q == 0 ? 1 : q, std::span<std::uint8_t, 128>(tables, 128));
  } else {
    if (p.size() < pos + kQuantHeaderBytes) {
      ++stats_.malformed_packets;
      return false;
    }
    const std::uint8_t precision = p[pos + 1];
    const std::size_t length = (std::size_t{p[pos + 2]} << 8) | p[pos + 3];
    pos += kQuantHeaderBytes;
    if (precision != 0) {
      ++stats_.unsupported_packets;  // 16-bit tables: not used by cameras
      return false;
    }
    if (length == 0) {
      // Q 255 tables are never cacheable; 128..254 reuse what came with an earlier frame.
      const std::size_t slot = static_cast<std::size_t>(q - 128);
      if (q == 255 || cached_length_[slot] == 0) {
        ++stats_.malformed_packets;
        return false;
      }
      table_bytes = cached_length_[slot];
      std::memcpy(tables, cached_tables_[slot].data(), table_bytes);
    } else {
      if ((length != 64 && length < 128) || p.size() < pos + length) {
        ++stats_.malformed_packets;
        return false;
      }
      table_bytes = length >= 128 ? 128 : 64;  // one table (VLC, FFmpeg) or luma + chroma
      std::memcpy(tables, p.data() + pos, table_bytes);
      pos += length;
      if (q < 255) {
        const std::size_t slot = static_cast<std::size_t>(q - 128);
        std::memcpy(cached_tables_[slot].data(), tables, table_bytes);
        cached_length_[slot] = static_cast<std::uint8_t>(table_bytes);
      }
    }
  }
  Writer w(frame_.data());
  w.u8(0xFF);
  w.u8(0xD8);  // SOI
  const std::size_t table_count = table_bytes / 64;
  for (std::size_t t = 0; t < table_count; ++t) {
    w.u8(0xFF);
    w.u8(0xDB);
    w.u16(2 + 1 + 64);
    w.u8(static_cast<std::uint8_t>(t));
    w.bytes(tables + 64 * t, 64);
  }
  if (type >= 64) {
    w.u8(0xFF);
    w.u8(0xDD);
    w.u16(4);
    w.u16(restart_interval);
  }
  const std::uint8_t chroma_table = table_count > 1 ? 1 : 0;
  w.u8(0xFF);
  w.u8(0xC0);  // SOF0, baseline
  w.u16(17);
  w.u8(8);
  w.u16(static_cast<std::size_t>(height));
  w.u16(static_cast<std::size_t>(width));
  w.u8(3);
  w.u8(1);
  w.u8(base_type == 0 ? 0x21 : 0x22);  // 4:2:2 or 4:2:0 luma sampling (§4.1)
  w.u8(0);
  w.u8(2);
  w.u8(0x11);
  w.u8(chroma_table);
  w.u8(3);
  w.u8(0x11);
  w.u8(chroma_table);
  w.dht(0x00, kDcLumaBits, kDcSymbols, sizeof kDcSymbols);
  w.dht(0x10, kAcLumaBits, kAcLumaSymbols, sizeof kAcLumaSymbols);
  w.dht(0x01, kDcChromaBits, kDcSymbols, sizeof kDcSymbols);
  w.dht(0x11, kAcChromaBits, kAcChromaSymbols, sizeof kAcChromaSymbols);
  w.u8(0xFF);
  w.u8(0xDA);  // SOS
  w.u16(12);
  w.u8(3);
  w.u8(1);
  w.u8(0x00);
  w.u8(2);
  w.u8(0x11);
  w.u8(3);
  w.u8(0x11);
  w.u8(0);
  w.u8(63);
  w.u8(0);
  header_size_ = w.size();
  frame_size_ = header_size_;
  scan_offset = pos;
  return true;
}

void JpegDepacketizer::push(const RtpPacket& packet, bool loss_before, Nanos arrival_ns, EncodedFrameSink& sink) {
  ++stats_.packets;
  if (loss_before && open_) {
    ++stats_.frames_dropped_damaged;
    discard_frame();
  }
  if (open_ && packet.timestamp != timestamp_) {
    ++stats_.frames_dropped_damaged;  // the previous frame never got its marker
    discard_frame();
  }
  const auto p = packet.payload;
  if (p.size() < kMainHeaderBytes) {
    ++stats_.malformed_packets;
    return;
  }
  const std::size_t offset = (std::size_t{p[1]} << 16) | (std::size_t{p[2]} << 8) | p[3];
  std::size_t scan = 0;
  if (offset == 0) {
    if (open_) {
      ++stats_.frames_dropped_damaged;
      discard_frame();
    }
    if (!start_frame(p, scan)) return;
    open_ = true;
    timestamp_ = packet.timestamp;
    next_offset_ = 0;
  } else {
    if (!open_ || offset != next_offset_) {
      // FFmpeg's depayloader does the same: a gap in offsets means a lost packet.
      ++stats_.fragments_dropped;
      if (open_) {
        ++stats_.frames_dropped_damaged;
        discard_frame();
      }
      return;
    }
    scan = kMainHeaderBytes;
    const std::uint8_t type = p[4];
    if (type >= 64 && type < 128) scan += kRestartHeaderBytes;
    if (scan > p.size()) {
      ++stats_.malformed_packets;
      ++stats_.frames_dropped_damaged;
      discard_frame();
      return;
    }
  }
  const std::size_t data_bytes = p.size() - scan;
  if (frame_size_ - header_size_ + data_bytes > max_scan_bytes_) {
    ++stats_.frames_dropped_oversize;
    discard_frame();
    return;
  }
  std::memcpy(frame_.data() + frame_size_, p.data() + scan, data_bytes);
  frame_size_ += data_bytes;
  next_offset_ += data_bytes;
  if (!packet.marker) return;
  if (frame_size_ < header_size_ + 2 || frame_[frame_size_ - 2] != 0xFF || frame_[frame_size_ - 1] != 0xD9) {
    frame_[frame_size_++] = 0xFF;
    frame_[frame_size_++] = 0xD9;  // EOI
  }
  EncodedFrame frame;
  frame.codec = VideoCodec::jpeg;
  frame.data = std::span<const std::uint8_t>(frame_.data(), frame_size_);
  frame.rtp_timestamp = packet.timestamp;
  frame.keyframe = true;
  frame.last_packet_ns = arrival_ns;
  ++stats_.frames_emitted;
  sink.on_frame(frame);
  discard_frame();
}

}  // namespace sen3bot::camera
