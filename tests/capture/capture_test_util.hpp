#pragma once
// Helpers shared by the capture tests and the capture generator.
#include <cstdint>
#include <deque>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/capture/format.hpp"
#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::capture::test {

using Bytes = std::vector<std::uint8_t>;

// A fresh path in a per-process scratch directory (removed by nobody: /tmp is cheap).
std::filesystem::path scratch_path(std::string_view name);
Bytes read_bytes(const std::filesystem::path& path);
void write_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);
// Checked-in capture data: <source>/tests/data/captures/<name>.
std::filesystem::path captures_dir();

// Builds capture bytes field by field, so malformed files can be made on purpose.
class FileBuilder {
 public:
  FileBuilder& header(const CaptureInfo& info);  // file header + channel table
  FileBuilder& record(hal::Nanos t_ns, std::uint8_t channel, RecordKind kind, std::span<const std::uint8_t> payload);
  FileBuilder& rx(hal::Nanos t_ns, std::uint8_t channel, std::span<const std::uint8_t> payload) {
    return record(t_ns, channel, RecordKind::rx, payload);
  }
  FileBuilder& tx(hal::Nanos t_ns, std::uint8_t channel, std::span<const std::uint8_t> payload) {
    return record(t_ns, channel, RecordKind::tx, payload);
  }
  FileBuilder& baud(hal::Nanos t_ns, std::uint8_t channel, std::uint32_t baud);
  FileBuilder& gap(hal::Nanos t_ns, std::uint64_t records, std::uint64_t bytes);
  FileBuilder& end(hal::Nanos t_ns, std::uint64_t written, std::uint64_t dropped);
  FileBuilder& raw(std::span<const std::uint8_t> more);
  [[nodiscard]] std::size_t size() const { return bytes_.size(); }
  [[nodiscard]] const Bytes& bytes() const { return bytes_; }
  Bytes& mutable_bytes() { return bytes_; }

 private:
  Bytes bytes_;
};

// Two channels, p2os (id 0, 9600 baud) and lms200 (id 1, 9600 baud), start times fixed.
CaptureInfo two_channel_info();

// An in-memory ByteStream with scripted reads and a cap on accepted write bytes.
class ScriptedStream final : public hal::ByteStream {
 public:
  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] std::string_view name() const override { return "scripted"; }

  void push_rx(Bytes chunk) { rx_.push_back(std::move(chunk)); }
  void push_read_error(Errc code) { errors_.push_back(code); }
  std::size_t max_write_bytes = SIZE_MAX;  // write() accepts at most this many per call
  Bytes written;                            // everything accepted

 private:
  std::deque<Bytes> rx_;
  std::deque<Errc> errors_;  // returned by read() before any rx chunk
};

}  // namespace sen3bot::capture::test
