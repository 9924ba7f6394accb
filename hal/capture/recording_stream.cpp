#include "sen3bot/capture/recording_stream.hpp"

namespace sen3bot::capture {

// The clamps only guard against an inner stream that over-reports; they never trigger in
// a correct one.
Result<std::size_t> RecordingStream::read(std::span<std::uint8_t> out) {
  Result<std::size_t> n = inner_.read(out);
  if (n && *n > 0) (void)writer_.record(clock_.now(), channel_, Direction::rx, out.first(*n < out.size() ? *n : out.size()));
  return n;
}

Result<std::size_t> RecordingStream::write(std::span<const std::uint8_t> data) {
  Result<std::size_t> n = inner_.write(data);
  if (n && *n > 0) (void)writer_.record(clock_.now(), channel_, Direction::tx, data.first(*n < data.size() ? *n : data.size()));
  return n;
}

void RecordingStream::note_baud_change(std::uint32_t baud) noexcept {
  (void)writer_.record_baud_change(clock_.now(), channel_, baud);
}

}  // namespace sen3bot::capture
