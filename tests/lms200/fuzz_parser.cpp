// Fuzz target: arbitrary bytes into both parser sides, in chunk sizes taken from the input,
// and every telegram that passes the CRC through every decoder. Checks invariants that must
// hold for any input: frames are CRC-valid and within LEN bounds, decoders never read past
// the frame, scan counts never exceed 401, B7 sub-ranges and B6 sample counts are in bounds.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace {

using namespace sen3bot::lms200;

constexpr MeasuringMode kModes[] = {
    MeasuringMode::range8_fields_dazzle, MeasuringMode::range8_reflector8,  MeasuringMode::range8_fields_abc,
    MeasuringMode::range16_reflector4,   MeasuringMode::range16_fields_ab,  MeasuringMode::range32_reflector2,
    MeasuringMode::range32_field_a,      MeasuringMode::range32_immediate,  MeasuringMode::reflectivity};

void check(bool ok) {
  if (!ok) std::abort();
}

// What any decoded B0, B6 or B7 must satisfy, whatever the bytes were.
void check_scan(FrameView f, const sen3bot::Result<ScanTelegram>& s, std::uint8_t code) {
  if (!s.ok()) return;
  check(f.code() == code && s->code == code);
  check(s->count <= kMaxValues);
  check(s->first_index >= 1 && s->last_index <= kMaxValues);
  check(s->last_index + 1 - s->first_index == s->count);
  if (code != kReplySubrangeScan) check(s->first_index == 1);
  if (code == kReplyMeanScan) check(s->mean_samples >= kMinMeanSamples && s->mean_samples <= kMaxMeanSamples);
  if (code != kReplyMeanScan) check(s->mean_samples == 0);
  check(static_cast<unsigned>(s->units) <= 2);
  for (std::size_t i = 0; i < s->count; ++i)
    for (MeasuringMode m : kModes) {
      const ScanValue v = decode_value(s->words[i], m);
      check((v.reason == InvalidReason::none) == ((v.flags & value_flag::kValid) != 0));
    }
}

void decode_all(FrameView f) {
  check(f.bytes.size() >= kFrameOverheadBytes + 1 && f.bytes.size() <= kMaxFrameBytes);
  check(f.len() >= 1 && f.len() <= kMaxLen);
  check(crc16(f.bytes.first(f.bytes.size() - 2)) == static_cast<std::uint16_t>(f.bytes[f.bytes.size() - 2] |
                                                                             (f.bytes[f.bytes.size() - 1] << 8)));
  (void)decode_mode_change(f);
  (void)decode_status(f);
  (void)decode_type(f);
  (void)decode_variant(f);
  (void)decode_read_config(f);
  (void)decode_write_config(f);
  check_scan(f, decode_scan(f), kReplyScan);
  check_scan(f, decode_mean_scan(f), kReplyMeanScan);
  check_scan(f, decode_subrange_scan(f), kReplySubrangeScan);
  // The dispatcher agrees with the decoder of the telegram's own code.
  auto any = decode_any_scan(f);
  check(any.ok() == ((f.code() == kReplyScan && decode_scan(f).ok()) ||
                     (f.code() == kReplyMeanScan && decode_mean_scan(f).ok()) ||
                     (f.code() == kReplySubrangeScan && decode_subrange_scan(f).ok())));
}

void run(Side side, const std::uint8_t* data, std::size_t size) {
  TelegramParser parser(side);
  std::size_t at = 0;
  std::size_t chunk = size > 0 ? (data[0] % 64) + 1 : 1;
  while (at < size) {
    const std::size_t n = chunk < size - at ? chunk : size - at;
    std::size_t pushed = 0;
    while (pushed < n) {
      pushed += parser.push({data + at + pushed, n - pushed});
      TelegramParser::Event e;
      while (parser.next(e))
        if (e.kind == TelegramParser::Kind::frame) decode_all(e.frame);
    }
    at += n;
    chunk = (chunk * 7 + 3) % 97 + 1;
  }
  while (parser.size() > 0) {
    const std::size_t before = parser.size();
    parser.drop_partial();
    TelegramParser::Event e;
    while (parser.next(e))
      if (e.kind == TelegramParser::Kind::frame) decode_all(e.frame);
    check(parser.size() < before);  // always progresses
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  run(Side::from_device, data, size);
  run(Side::from_host, data, size);
  return 0;
}
