#pragma once
// Human-readable listing of a capture (`sen3bot capture dump FILE`): the header, the channel
// table, then one line per record (time since start in seconds, channel name, kind, length,
// payload in hex, 16 bytes a line), then the totals.
#include <cstdio>
#include <filesystem>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::capture {

Status dump(const CaptureFile& capture, std::FILE* out);
// Loads and validates first; a malformed file prints nothing and returns the error.
Status dump(const std::filesystem::path& path, std::FILE* out);

}  // namespace sen3bot::capture
