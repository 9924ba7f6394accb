#pragma once
// Private to hal/posix: line-setting queries shared by SerialPort and PtyPair (whose master
// reports the slave's termios).
#include <cstdint>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/hal/serial.hpp"

namespace sen3bot::hal::posix {

Result<SerialLineSettings> query_line_settings(int fd, std::string_view name);
Result<std::uint32_t> query_baud(int fd, std::string_view name);

// Raw 8N1 at baud in one tcsetattr/TCSETS2, then read back and compared.
Status configure_raw_line(int fd, std::string_view name, std::uint32_t baud);

}  // namespace sen3bot::hal::posix
