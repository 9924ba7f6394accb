// Fuzz target: arbitrary bytes through CaptureReader, CaptureFile, dump and ReplayStream.
// The reader must reject or accept without crashing, reading out of bounds or looping, and
// the cursor and whole-file parsers must agree.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <vector>

#include "sen3bot/capture/dump.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/hal/clock.hpp"

namespace {

void check(bool condition) {
  if (!condition) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::capture;
  const std::span<const std::uint8_t> bytes(data, size);

  bool cursor_ok = false;
  std::size_t cursor_records = 0;
  if (auto reader = CaptureReader::open(bytes)) {
    for (;;) {
      auto next = reader->next();
      if (!next) break;
      if (!next->has_value()) {
        cursor_ok = true;
        break;
      }
      const Record& r = **next;
      check(r.payload.data() >= data && r.payload.data() + r.payload.size() <= data + size);
      check(r.payload.size() <= kMaxPayloadBytes);
      ++cursor_records;
    }
  }

  auto file = CaptureFile::parse(std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
  check(file.ok() == cursor_ok);
  if (!file) return 0;
  check(file->records().size() == cursor_records);

  static std::FILE* sink = std::fopen("/dev/null", "w");
  if (sink != nullptr) (void)dump(*file, sink);

  for (const ChannelDecl& channel : file->info().channels) {
    sen3bot::hal::SimClock clock;
    ReplayStream replay(*file, channel.id, clock, ReplayTiming::as_fast_as_possible);
    std::uint8_t buf[97];  // odd size: exercises partial chunk reads
    std::size_t received = 0;
    for (auto n = replay.read(buf); n; n = replay.read(buf)) {
      check(*n > 0 && *n <= sizeof buf);
      received += *n;
    }
    check(received == file->stream_bytes(channel.id, Direction::rx).size());
  }
  return 0;
}
