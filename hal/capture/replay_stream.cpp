#include "sen3bot/capture/replay_stream.hpp"

#include <cstdint>
#include <cstring>

namespace sen3bot::capture {

namespace {

// Record times come from a file; a time near INT64_MAX must saturate, not overflow.
hal::Nanos due_time(hal::Nanos start_ns, hal::Nanos t_ns) noexcept {
  hal::Nanos due_ns = 0;
  if (__builtin_add_overflow(start_ns, t_ns, &due_ns)) return t_ns > 0 ? INT64_MAX : INT64_MIN;
  return due_ns;
}

}  // namespace

ReplayStream::ReplayStream(const CaptureFile& capture, std::uint8_t channel, hal::Clock& clock, ReplayTiming timing)
    : clock_(clock), timing_(timing), replay_start_ns_(clock.now()) {
  const ChannelDecl* decl = capture.channel(channel);
  name_ = "replay:";
  name_ += decl != nullptr ? decl->name : std::string("channel-") + std::to_string(channel);
  for (const Record& r : capture.records()) {
    if (r.channel != channel) continue;
    switch (r.kind) {
      case RecordKind::rx:
        if (r.payload.empty()) break;  // nothing to deliver
        chunks_.push_back(Chunk{r.t_ns, rx_bytes_.size(), r.payload.size()});
        rx_bytes_.insert(rx_bytes_.end(), r.payload.begin(), r.payload.end());
        break;
      case RecordKind::tx:
        tx_expected_.insert(tx_expected_.end(), r.payload.begin(), r.payload.end());
        break;
      case RecordKind::baud_change:
        baud_changes_.push_back(BaudChange{r.t_ns, r.baud});
        break;
      case RecordKind::gap:
      case RecordKind::end:
        break;
    }
  }
  tx_.expected_bytes = tx_expected_.size();
}

std::optional<hal::Nanos> ReplayStream::next_due_ns() const noexcept {
  if (finished()) return std::nullopt;
  return due_time(replay_start_ns_, chunks_[next_chunk_].t_ns);
}

Result<std::size_t> ReplayStream::read(std::span<std::uint8_t> out) {
  if (finished()) return Error(Errc::disconnected, "replay finished");
  if (out.empty()) return std::size_t{0};
  const Chunk& chunk = chunks_[next_chunk_];
  const hal::Nanos due_ns = due_time(replay_start_ns_, chunk.t_ns);
  if (clock_.now() < due_ns) {
    if (timing_ == ReplayTiming::original) return std::size_t{0};
    if (clock_.simulated()) clock_.sleep_until(due_ns);  // a SimClock jumps; never blocks
  }
  const std::size_t left = chunk.size - chunk_offset_;
  const std::size_t n = out.size() < left ? out.size() : left;
  std::memcpy(out.data(), rx_bytes_.data() + chunk.begin + chunk_offset_, n);
  chunk_offset_ += n;
  rx_delivered_bytes_ += n;
  if (chunk_offset_ == chunk.size) {
    ++next_chunk_;
    chunk_offset_ = 0;
  }
  return n;
}

Result<std::size_t> ReplayStream::write(std::span<const std::uint8_t> data) {
  for (const std::uint8_t actual : data) {
    const std::uint64_t at = tx_.written_bytes++;
    const bool recorded = at < tx_expected_.size();
    if (recorded && tx_expected_[static_cast<std::size_t>(at)] == actual) {
      ++tx_.matched_bytes;
      continue;
    }
    ++tx_.mismatched_bytes;
    if (tx_.first_mismatch_offset < 0) {
      tx_.first_mismatch_offset = static_cast<std::int64_t>(at);
      tx_.first_mismatch_expected = recorded ? tx_expected_[static_cast<std::size_t>(at)] : -1;
      tx_.first_mismatch_actual = actual;
    }
  }
  return data.size();
}

}  // namespace sen3bot::capture
