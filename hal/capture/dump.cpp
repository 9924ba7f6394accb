#include "sen3bot/capture/dump.hpp"

#include <cerrno>
#include <cinttypes>
#include <ctime>

namespace sen3bot::capture {

namespace {

constexpr std::size_t kHexBytesPerLine = 16;
constexpr int kHexIndent = 46;  // width of "  time  channel kind length" before the hex column

void print_wall_time(std::FILE* out, std::int64_t wall_ns) {
  if (wall_ns == 0) {
    std::fputs("unknown", out);
    return;
  }
  // Floor division without multiplying back: any i64 from a hostile file must not overflow.
  std::int64_t seconds = wall_ns / hal::kNanosPerSecond;
  std::int64_t fraction_ns = wall_ns % hal::kNanosPerSecond;
  if (fraction_ns < 0) {
    fraction_ns += hal::kNanosPerSecond;
    seconds -= 1;
  }
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm utc{};
  char text[32];
  if (gmtime_r(&t, &utc) == nullptr || std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc) == 0) {
    std::fprintf(out, "%" PRId64 " ns since the Unix epoch", wall_ns);
    return;
  }
  std::fprintf(out, "%s.%09" PRId64 "Z", text, fraction_ns);
}

struct SecondsText {
  char text[32];
};

SecondsText format_seconds(hal::Nanos ns) {
  // Integer arithmetic: a double would lose nanoseconds after a few months of uptime.
  SecondsText s{};
  const char* sign = ns < 0 ? "-" : "";
  const std::uint64_t magnitude = ns < 0 ? 0 - static_cast<std::uint64_t>(ns) : static_cast<std::uint64_t>(ns);
  std::snprintf(s.text, sizeof s.text, "%s%" PRIu64 ".%09" PRIu64, sign, magnitude / 1'000'000'000u,
                magnitude % 1'000'000'000u);
  return s;
}

}  // namespace

Status dump(const CaptureFile& capture, std::FILE* out) {
  const CaptureInfo& info = capture.info();
  std::fprintf(out, "sen3bot capture, format version %u\n", kFormatVersion);
  std::fputs("start wall clock: ", out);
  print_wall_time(out, info.start_wall_ns);
  std::fprintf(out, "\nstart monotonic:  %s s (record times are relative to this)\nchannels: %zu\n",
               format_seconds(info.start_monotonic_ns).text, info.channels.size());
  for (const ChannelDecl& c : info.channels) {
    std::fprintf(out, "  %3u  %-32s", c.id, c.name.c_str());
    if (c.baud != 0) std::fprintf(out, "  %" PRIu32 " baud", c.baud);
    std::fputc('\n', out);
  }
  std::fprintf(out, "records: %zu\n", capture.records().size());
  std::fprintf(out, "  %18s  %-12s %-4s %6s  %s\n", "time_s", "channel", "kind", "length", "bytes");

  for (const Record& r : capture.records()) {
    const ChannelDecl* c = capture.channel(r.channel);
    const char* channel_name = c != nullptr ? c->name.c_str() : "-";
    std::fprintf(out, "  %18s  %-12s %-4.*s %6zu", format_seconds(r.t_ns).text, channel_name, static_cast<int>(to_string(r.kind).size()),
                 to_string(r.kind).data(), r.payload.size());
    switch (r.kind) {
      case RecordKind::rx:
      case RecordKind::tx:
        for (std::size_t i = 0; i < r.payload.size(); ++i) {
          if (i % kHexBytesPerLine == 0) {
            if (i > 0) std::fprintf(out, "\n%*s", kHexIndent, "");
            std::fputc(' ', out);
          }
          std::fprintf(out, " %02x", r.payload[i]);
        }
        break;
      case RecordKind::baud_change:
        std::fprintf(out, "  -> %" PRIu32 " baud", r.baud);
        break;
      case RecordKind::gap:
        std::fprintf(out, "  %" PRIu64 " records (%" PRIu64 " payload bytes) dropped here", r.dropped_records,
                     r.dropped_bytes);
        break;
      case RecordKind::end:
        std::fprintf(out, "  %" PRIu64 " records written, %" PRIu64 " dropped", r.written_records, r.dropped_records);
        break;
    }
    std::fputc('\n', out);
  }
  if (!capture.complete()) std::fputs("no end record: the capture was not closed cleanly\n", out);
  if (std::ferror(out)) return Error::from_errno(Errc::io, "capture dump: write", errno);
  return {};
}

Status dump(const std::filesystem::path& path, std::FILE* out) {
  auto capture = CaptureFile::load(path);
  if (!capture) return capture.error();
  return dump(*capture, out);
}

}  // namespace sen3bot::capture
