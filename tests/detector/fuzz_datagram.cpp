// Fuzz target: any bytes through the gate give a frame or a counted refusal; an accepted
// frame's boxes lie inside the image.
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/detector/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::detector;
  // The gate's clocks at the seeds' capture time, so fresh datagrams get past the clock checks.
  constexpr std::int64_t kUnixNow = 1'764'000'000'000'000'000;
  DetectionGate gate;
  sen3bot::detector::Detections out;
  const std::span<const std::uint8_t> bytes(data, size);
  std::uint64_t seen = 0;
  for (int i = 0; i < 2; ++i) {  // twice: the second is a replay
    if (gate.accept(bytes, 5'000'000'000, kUnixNow, out)) {
      for (std::size_t b = 0; b < out.count; ++b)
        if (!(out.boxes[b].u0 < out.boxes[b].u1 && out.boxes[b].u1 <= 1280.0f && out.boxes[b].v1 <= 720.0f)) __builtin_trap();
    }
  }
  seen += gate.accepted();
  for (std::size_t r = 0; r < kRejects; ++r) seen += gate.rejected(static_cast<Reject>(r));
  if (seen != 2) __builtin_trap();  // every datagram is accepted or counted, once
  return 0;
}
