#pragma once
// Decodes the LMS200 traffic of a wire capture into JSON lines, one object per telegram,
// ACK/NAK or baud change, in capture order (what `sen3bot decode lms200 CAPTURE` prints).
#include <cstdio>
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

}  // namespace sen3bot::lms200
