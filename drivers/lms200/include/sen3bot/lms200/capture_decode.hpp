#pragma once
// Decodes the LMS200 traffic of a wire capture into JSON lines, one object per telegram,
// ACK/NAK or baud change, in capture order (what `sen3bot decode lms200 CAPTURE` prints).
#include <cstdio>
#include <functional>
#include <span>
#include <string_view>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::lms200 {

struct CaptureDecodeSummary {
  std::size_t requests = 0;
  std::size_t replies = 0;
  std::size_t scans = 0;
  std::size_t acks = 0;
  std::size_t naks = 0;
  std::uint64_t crc_errors = 0;
  std::uint64_t garbage_bytes = 0;
};

// Decodes channel `channel_name` (empty: the first channel whose name contains "lms").
Result<CaptureDecodeSummary> decode_capture_json(const capture::CaptureFile& capture, std::string_view channel_name,
                                                 std::FILE* out);

// One complete scan of a capture, in metres, as the driver would publish it.
struct CapturedScan {
  double t_s = 0;                   // when the scanner measured it: its last byte's arrival less its transmission
  std::span<const float> ranges_m;  // NaN where the scanner reported no distance
  double angle_min_rad = 0;         // the first beam, counter-clockwise from straight ahead
  double increment_rad = 0;
};
using ScanVisitor = std::function<void(const CapturedScan&)>;

// Calls visit for every complete scan (B0 or B6; the variant from its number of values) of the
// channel, in capture order. Interlaced partial scans and subrange scans are counted in the
// summary but not visited.
Result<CaptureDecodeSummary> for_each_scan(const capture::CaptureFile& capture, std::string_view channel_name,
                                           const ScanVisitor& visit);

}  // namespace sen3bot::lms200
