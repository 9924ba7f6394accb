#include "capture_test_util.hpp"

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace sen3bot::capture::test {

std::filesystem::path scratch_path(std::string_view name) {
  static std::atomic<int> counter{0};
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("sen3bot-capture-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / (std::to_string(counter.fetch_add(1)) + "-" + std::string(name));
}

Bytes read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::filesystem::path captures_dir() { return std::filesystem::path(SEN3BOT_SOURCE_DIR) / "tests/data/captures"; }

FileBuilder& FileBuilder::header(const CaptureInfo& info) {
  const auto h = encode_file_header(info);
  bytes_.insert(bytes_.end(), h.begin(), h.end());
  for (const ChannelDecl& c : info.channels) append_channel_decl(bytes_, c);
  return *this;
}

FileBuilder& FileBuilder::record(hal::Nanos t_ns, std::uint8_t channel, RecordKind kind,
                                 std::span<const std::uint8_t> payload) {
  const auto h = encode_record_header(t_ns, channel, kind, static_cast<std::uint32_t>(payload.size()));
  bytes_.insert(bytes_.end(), h.begin(), h.end());
  bytes_.insert(bytes_.end(), payload.begin(), payload.end());
  return *this;
}

FileBuilder& FileBuilder::baud(hal::Nanos t_ns, std::uint8_t channel, std::uint32_t baud) {
  std::uint8_t p[kBaudPayloadBytes];
  le::put_u32(p, baud);
  return record(t_ns, channel, RecordKind::baud_change, p);
}

FileBuilder& FileBuilder::gap(hal::Nanos t_ns, std::uint64_t records, std::uint64_t bytes) {
  std::uint8_t p[kGapPayloadBytes];
  le::put_u64(p, records);
  le::put_u64(p + 8, bytes);
  return record(t_ns, kNoChannel, RecordKind::gap, p);
}

FileBuilder& FileBuilder::end(hal::Nanos t_ns, std::uint64_t written, std::uint64_t dropped) {
  std::uint8_t p[kEndPayloadBytes];
  le::put_u64(p, written);
  le::put_u64(p + 8, dropped);
  return record(t_ns, kNoChannel, RecordKind::end, p);
}

FileBuilder& FileBuilder::raw(std::span<const std::uint8_t> more) {
  bytes_.insert(bytes_.end(), more.begin(), more.end());
  return *this;
}

CaptureInfo two_channel_info() {
  CaptureInfo info;
  info.start_wall_ns = 1'704'067'200 * hal::kNanosPerSecond;  // 2024-01-01T00:00:00Z
  info.start_monotonic_ns = hal::seconds(1000);
  info.channels = {ChannelDecl{0, "p2os", 9600}, ChannelDecl{1, "lms200", 9600}};
  return info;
}

Result<std::size_t> ScriptedStream::read(std::span<std::uint8_t> out) {
  if (!errors_.empty()) {
    const Errc code = errors_.front();
    errors_.pop_front();
    return Error(code, "scripted error");
  }
  if (rx_.empty() || out.empty()) return std::size_t{0};
  Bytes& chunk = rx_.front();
  const std::size_t n = out.size() < chunk.size() ? out.size() : chunk.size();
  std::memcpy(out.data(), chunk.data(), n);
  chunk.erase(chunk.begin(), chunk.begin() + static_cast<long>(n));
  if (chunk.empty()) rx_.pop_front();
  return n;
}

Result<std::size_t> ScriptedStream::write(std::span<const std::uint8_t> data) {
  const std::size_t n = data.size() < max_write_bytes ? data.size() : max_write_bytes;
  written.insert(written.end(), data.begin(), data.begin() + static_cast<long>(n));
  return n;
}

}  // namespace sen3bot::capture::test
