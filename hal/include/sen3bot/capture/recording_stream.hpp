#pragma once
// RecordingStream: a ByteStream decorator that passes everything through to the wrapped
// stream and records it: each successful non-empty read as rx, each accepted write as tx
// (only the bytes the inner stream accepted). Recording never fails the I/O: a full capture
// buffer drops the record and the writer counts it.
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/capture/writer.hpp"
#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::capture {

class RecordingStream final : public hal::ByteStream {
 public:
  // `clock` must be the clock whose reading was given as the writer's start_monotonic_ns.
  RecordingStream(hal::ByteStream& inner, CaptureWriter& writer, std::uint8_t channel, hal::Clock& clock) noexcept
      : inner_(inner), writer_(writer), clock_(clock), channel_(channel) {}

  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] int poll_fd() const override { return inner_.poll_fd(); }
  [[nodiscard]] std::string_view name() const override { return inner_.name(); }

  // Call after switching the inner link's baud rate, so replays know where it happened.
  void note_baud_change(std::uint32_t baud) noexcept;

  [[nodiscard]] std::uint8_t channel() const noexcept { return channel_; }

 private:
  hal::ByteStream& inner_;
  CaptureWriter& writer_;
  hal::Clock& clock_;
  std::uint8_t channel_;
};

}  // namespace sen3bot::capture
