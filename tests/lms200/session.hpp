#pragma once
// A recorded LMS200 session, shared by the data generator and the replay test: the emulator
// powered on at 9600 baud in cm; the driver asks for 38400, 180 deg / 0.5 deg, mm, so the
// capture holds a baud switch, a variant change and a configuration write, then streamed
// scans with a few injected faults, then a clean stop.
#include <filesystem>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/lms200/device.hpp"

namespace sen3bot::lms200::testing {

inline constexpr std::uint8_t kSessionChannel = 0;
inline constexpr hal::Nanos kSessionStepNs = hal::millis(1);

Lms200Config session_driver_config();
Status record_session(const std::filesystem::path& path);

}  // namespace sen3bot::lms200::testing
