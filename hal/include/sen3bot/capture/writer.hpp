#pragma once
// CaptureWriter: records wire traffic into a capture file without disturbing real-time code.
//
// record() only copies into a byte ring allocated at construction: no allocation, no lock, no
// system call. flush() moves what is buffered to the file. When the ring is full, record()
// drops the record and counts it; the next record that fits is preceded by a gap record, and
// close() writes any remaining gap plus an end record holding the totals.
//
// Threads: one recording thread (record*, the producer) and any flushing threads (flush,
// the consumer side, serialised by a mutex the producer never touches). open() must finish
// before recording starts; close() must run after the recording thread has stopped calling
// record*. Several devices on several threads: give each thread its own writer and file.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <span>

#include "sen3bot/capture/format.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::capture {

class CaptureWriter {
 public:
  // The ring holds `buffer_capacity_bytes`; a record needs 16 bytes of header plus its
  // payload (plus 32 bytes once after drops, for the gap record).
  explicit CaptureWriter(std::size_t buffer_capacity_bytes);
  ~CaptureWriter();  // closes the file if still open, ignoring errors
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;

  // Creates (truncates) `path` and writes the header and channel table. Channel ids must be
  // unique and not kNoChannel, names valid (valid_channel_name), at most kMaxChannels.
  Status open(const std::filesystem::path& path, const CaptureInfo& info);

  // Producer side. `now_ns` is a reading of the same monotonic clock as
  // info.start_monotonic_ns; the stored time is the difference, clamped so it never
  // decreases. Payloads over kMaxPayloadBytes are split into several records with the same
  // time. Returns false if the record was dropped (buffer full), or not written because the
  // writer is not open or the channel was not declared (counted in rejected_records()).
  bool record(hal::Nanos now_ns, std::uint8_t channel, Direction direction,
              std::span<const std::uint8_t> payload) noexcept;
  // The link on `channel` switched to `baud` at `now_ns`.
  bool record_baud_change(hal::Nanos now_ns, std::uint8_t channel, std::uint32_t baud) noexcept;

  // Consumer side: writes everything buffered so far to the file.
  Status flush();
  // Flushes, appends the final gap (if any) and the end record, closes the file.
  Status close();

  [[nodiscard]] bool is_open() const noexcept { return open_.load(std::memory_order_acquire); }
  [[nodiscard]] std::size_t buffer_capacity_bytes() const noexcept { return capacity_bytes_; }
  [[nodiscard]] std::size_t buffered_bytes() const noexcept;
  // rx, tx and baud_change records accepted into the buffer.
  [[nodiscard]] std::uint64_t records_written() const noexcept { return records_written_.load(std::memory_order_relaxed); }
  // Records lost because the buffer was full, and their payload bytes.
  [[nodiscard]] std::uint64_t dropped_records() const noexcept { return dropped_records_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t dropped_bytes() const noexcept { return dropped_bytes_.load(std::memory_order_relaxed); }
  // Records refused for an undeclared channel or while closed; not part of the file.
  [[nodiscard]] std::uint64_t rejected_records() const noexcept { return rejected_records_.load(std::memory_order_relaxed); }

 private:
  bool append(hal::Nanos now_ns, std::uint8_t channel, RecordKind kind,
              std::span<const std::uint8_t> payload) noexcept;
  void ring_put(std::uint64_t at, const std::uint8_t* data, std::size_t size) noexcept;
  Status write_all(const std::uint8_t* data, std::size_t size);
  Status flush_locked();

  const std::size_t capacity_bytes_;
  std::unique_ptr<std::uint8_t[]> ring_;
  // Monotonic byte counters; position in the ring is counter % capacity.
  std::atomic<std::uint64_t> head_{0};  // written by the producer
  std::atomic<std::uint64_t> tail_{0};  // written by the consumer

  std::atomic<bool> open_{false};
  std::array<bool, 256> declared_{};   // set by open() before recording starts
  hal::Nanos start_monotonic_ns_ = 0;

  // Producer state; atomics only so close() and the getters may read them from elsewhere.
  std::atomic<hal::Nanos> last_t_ns_{0};
  std::atomic<std::uint64_t> records_written_{0};
  std::atomic<std::uint64_t> dropped_records_{0};
  std::atomic<std::uint64_t> dropped_bytes_{0};
  std::atomic<std::uint64_t> rejected_records_{0};
  std::atomic<std::uint64_t> unreported_drop_records_{0};  // not yet covered by a gap record
  std::atomic<std::uint64_t> unreported_drop_bytes_{0};

  std::mutex consumer_mutex_;  // serialises flush() and close(); never taken by record()
  int fd_ = -1;
};

}  // namespace sen3bot::capture
