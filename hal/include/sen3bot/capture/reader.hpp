#pragma once
// Reading capture files with strict validation. Every malformed input is an Error
// (Errc::protocol) whose message starts with "capture offset N:" (the byte offset of the
// offending field); nothing reads outside the given bytes, and every loop advances.
//
// CaptureReader is a cursor over bytes the caller keeps alive; CaptureFile owns the bytes and
// the fully validated record list (what replay and dump use).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "sen3bot/capture/format.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::capture {

struct Record {
  std::uint64_t file_offset = 0;  // offset of the record header
  hal::Nanos t_ns = 0;            // since capture start
  std::uint8_t channel = kNoChannel;
  RecordKind kind = RecordKind::rx;
  std::span<const std::uint8_t> payload;  // into the reader's bytes

  // Decoded payloads of the non-data kinds (zero for other kinds).
  std::uint32_t baud = 0;                 // baud_change: the new rate
  std::uint64_t dropped_records = 0;      // gap: records lost here; end: total lost
  std::uint64_t dropped_bytes = 0;        // gap: their payload bytes
  std::uint64_t written_records = 0;      // end: rx + tx + baud_change records in the file
};

class CaptureReader {
 public:
  // Validates the file header and channel table.
  static Result<CaptureReader> open(std::span<const std::uint8_t> bytes);

  [[nodiscard]] const CaptureInfo& info() const noexcept { return info_; }
  [[nodiscard]] const ChannelDecl* channel(std::uint8_t id) const noexcept;

  // The next record; std::nullopt once the bytes end cleanly (after the end record, or at a
  // record boundary in a capture that was never closed). An error is sticky.
  Result<std::optional<Record>> next();

  [[nodiscard]] bool saw_end_record() const noexcept { return saw_end_; }
  [[nodiscard]] std::uint64_t offset() const noexcept { return offset_; }

 private:
  explicit CaptureReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  Error fail(Error error);

  std::span<const std::uint8_t> bytes_;
  CaptureInfo info_;
  std::array<std::int16_t, 256> channel_index_{};  // id -> index into info_.channels, -1 if none
  std::uint64_t offset_ = 0;
  hal::Nanos last_t_ns_ = 0;
  std::uint64_t data_records_ = 0;      // rx + tx + baud_change seen
  std::uint64_t gap_dropped_records_ = 0;
  bool saw_end_ = false;
  std::optional<Error> error_;
};

class CaptureFile {
 public:
  // Parses and validates a whole capture; takes ownership of the bytes.
  static Result<CaptureFile> parse(std::vector<std::uint8_t> bytes);
  static Result<CaptureFile> load(const std::filesystem::path& path);

  CaptureFile(CaptureFile&&) noexcept = default;
  CaptureFile& operator=(CaptureFile&&) noexcept = default;
  CaptureFile(const CaptureFile&) = delete;  // records point into bytes_
  CaptureFile& operator=(const CaptureFile&) = delete;

  [[nodiscard]] const CaptureInfo& info() const noexcept { return info_; }
  [[nodiscard]] std::span<const Record> records() const noexcept { return records_; }
  [[nodiscard]] std::span<const std::uint8_t> bytes() const noexcept { return bytes_; }
  // True when the capture ends with an end record (the writer was closed cleanly).
  [[nodiscard]] bool complete() const noexcept { return complete_; }
  [[nodiscard]] const ChannelDecl* channel(std::uint8_t id) const noexcept;
  [[nodiscard]] const ChannelDecl* find_channel(std::string_view name) const noexcept;
  // Concatenated payloads of one channel's rx or tx records.
  [[nodiscard]] std::vector<std::uint8_t> stream_bytes(std::uint8_t channel, Direction direction) const;

 private:
  CaptureFile() = default;
  std::vector<std::uint8_t> bytes_;
  CaptureInfo info_;
  std::vector<Record> records_;
  bool complete_ = false;
};

}  // namespace sen3bot::capture
