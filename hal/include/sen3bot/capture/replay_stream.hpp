#pragma once
// ReplayStream: a ByteStream that plays one channel of a capture back to a driver.
//
// Reads deliver the channel's rx records in order. A record becomes readable once
// clock.now() - replay_start >= its time (ReplayTiming::original), so with a PosixClock the
// session replays in real time and with a SimClock it follows the simulated time line. In
// ReplayTiming::as_fast_as_possible a read with nothing due moves a simulated clock forward
// to the next record (sleep_until on a SimClock) and returns it; with a real clock it just
// ignores the timestamps. One read never crosses a record boundary, and returns fewer bytes
// when the caller's buffer is smaller. After the last rx byte, reads return
// Errc::disconnected ("replay finished").
//
// Writes are always fully accepted and compared byte for byte with the channel's recorded
// tx stream (see TxComparison). Construction copies what it needs from the capture; read()
// and write() never allocate.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::capture {

enum class ReplayTiming : std::uint8_t { original, as_fast_as_possible };

// "Did the driver send exactly what it sent when recorded?"
struct TxComparison {
  std::uint64_t expected_bytes = 0;    // tx bytes recorded for the channel
  std::uint64_t written_bytes = 0;     // bytes the driver wrote during the replay
  std::uint64_t matched_bytes = 0;     // written bytes equal to the recorded byte at their offset
  std::uint64_t mismatched_bytes = 0;  // the others, including any written past the recording
  std::int64_t first_mismatch_offset = -1;  // offset in the tx stream; -1 if none
  int first_mismatch_expected = -1;         // recorded byte there; -1 if past the recording
  int first_mismatch_actual = -1;           // byte the driver wrote there

  // Everything matched and nothing is missing.
  [[nodiscard]] bool identical() const noexcept {
    return mismatched_bytes == 0 && written_bytes == expected_bytes;
  }
};

class ReplayStream final : public hal::ByteStream {
 public:
  // Replays `channel` of `capture`; the replay time line starts at clock.now(). A channel
  // with no rx records is finished at once.
  ReplayStream(const CaptureFile& capture, std::uint8_t channel, hal::Clock& clock, ReplayTiming timing);

  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] std::string_view name() const override { return name_; }

  // Restarts the time line (not the position) at `start_ns` on the replay clock.
  void set_replay_start(hal::Nanos start_ns) noexcept { replay_start_ns_ = start_ns; }
  [[nodiscard]] hal::Nanos replay_start_ns() const noexcept { return replay_start_ns_; }
  // Clock time at which the next unread rx record is due; nullopt when finished. Lets a
  // lockstep harness advance one SimClock to the earliest of several replays.
  [[nodiscard]] std::optional<hal::Nanos> next_due_ns() const noexcept;
  [[nodiscard]] bool finished() const noexcept { return next_chunk_ == chunks_.size(); }

  [[nodiscard]] const TxComparison& tx_comparison() const noexcept { return tx_; }
  [[nodiscard]] std::uint64_t rx_bytes_delivered() const noexcept { return rx_delivered_bytes_; }
  [[nodiscard]] std::uint64_t rx_bytes_total() const noexcept { return rx_bytes_.size(); }
  // Baud changes recorded on the channel, as (time since capture start, baud).
  struct BaudChange {
    hal::Nanos t_ns;
    std::uint32_t baud;
  };
  [[nodiscard]] std::span<const BaudChange> baud_changes() const noexcept { return baud_changes_; }

 private:
  struct Chunk {
    hal::Nanos t_ns;     // since capture start
    std::size_t begin;   // into rx_bytes_
    std::size_t size;
  };

  hal::Clock& clock_;
  ReplayTiming timing_;
  std::string name_;
  hal::Nanos replay_start_ns_;
  std::vector<std::uint8_t> rx_bytes_;
  std::vector<Chunk> chunks_;
  std::vector<std::uint8_t> tx_expected_;
  std::vector<BaudChange> baud_changes_;
  std::size_t next_chunk_ = 0;
  std::size_t chunk_offset_ = 0;
  std::uint64_t rx_delivered_bytes_ = 0;
  TxComparison tx_;
};

}  // namespace sen3bot::capture
