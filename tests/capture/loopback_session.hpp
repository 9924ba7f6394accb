#pragma once
// The scripted session behind tests/data/captures/*.s3bcap.
//
// Two channels: "p2os" (a Pioneer base, P2OS packets FA FB len payload checksum) and "lms200"
// (a SICK LMS200, telegrams STX addr len command data CRC16). Each channel's script is a list
// of exchanges: the firmware sends a request, the device answers with zero or more replies.
// The byte content of both directions is fixed by the script; only the timing and the way
// the kernel splits the bytes into reads vary between live recordings.
//
// Regenerate the checked-in captures (the files are the test data; regenerate only when the
// script or the format changes, and commit the new files):
//   cmake --build build-cap --target capture_generate
//   build-cap/tests/capture/capture_generate --data-dir tests/data
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "capture_test_util.hpp"
#include "sen3bot/capture/format.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::capture::test {

inline constexpr std::uint8_t kP2osChannel = 0;
inline constexpr std::uint8_t kLms200Channel = 1;
inline constexpr std::uint32_t kStartBaud = 9600;   // both devices power up at 9600 baud
inline constexpr std::uint32_t kLmsFastBaud = 38400;  // the LMS200 is switched up mid-session
// The firmware side reads at most this many bytes at a time; replays must use the same.
inline constexpr std::size_t kFirmwareReadBytes = 512;

struct Reply {
  hal::Nanos delay_ns;  // pause before the device sends it
  Bytes bytes;
};

struct Exchange {
  Bytes request;                       // firmware -> device
  std::vector<Reply> replies;          // device -> firmware
  std::optional<std::uint32_t> baud_after;  // the link switches baud once the replies are in
};

using Script = std::vector<Exchange>;

Bytes p2os_packet(std::span<const std::uint8_t> payload);
Bytes lms200_telegram(std::uint8_t address, std::span<const std::uint8_t> command_and_data);
std::uint16_t lms200_crc16(std::span<const std::uint8_t> bytes);

Script p2os_script();
Script lms200_script();
// All requests / all replies of a script, concatenated: the expected tx / rx streams.
Bytes script_tx(const Script& script);
Bytes script_rx(const Script& script);

CaptureInfo session_info(std::int64_t start_wall_ns, hal::Nanos start_monotonic_ns);

// One channel of the firmware side: the stream it talks through and its script.
struct FirmwareChannel {
  hal::ByteStream& stream;
  const Script& script;
  RecordingStream* recorder = nullptr;  // told about baud changes, if recording
};

// Plays the firmware side of both scripts over the given streams, checking every byte the
// devices send. `wait` is called when no channel made progress; it returns false to give up.
Status run_firmware_side(std::span<FirmwareChannel> channels, const std::function<bool()>& wait);

// Records a live session over two real pseudo-terminals (device emulators on threads at the
// master ends) into `path`, with a PosixClock and a background flushing thread.
Status record_loopback_session(const std::filesystem::path& path);

// Writes the same session with exact, computed timing (SimClock, serial transfer times at the
// current baud, long replies split into 64-byte reads): byte-identical on every run.
Status write_synthetic_session(const std::filesystem::path& path);

}  // namespace sen3bot::capture::test
