#pragma once
// Small pieces every command of both binaries shares: strict number parsing and a scope that
// turns SIGINT/SIGTERM into a stop request.
#include <signal.h>
#include <time.h>

#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/lms200/protocol.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::firmware {

// The whole text must be a finite number (no trailing characters, no NaN or infinity).
bool parse_double(std::string_view text, double& out);
// A secret kept in a file of its own (a broker password): its first line, trailing blanks cut.
// False with the problem when the file cannot be read or the line is empty. Passwords never go
// on a command line, where any user of the host could read them.
bool read_secret(const std::string& path, std::string& out, std::string& problem);
// The time of a POSIX clock (CLOCK_MONOTONIC, CLOCK_REALTIME) in ns.
std::int64_t clock_ns(clockid_t clock) noexcept;

// The broker options the fleet's programs share: --broker, --username, --password-file,
// --ca-file, --client-id.
struct BrokerArgs {
  std::string broker;
  std::string username;
  std::string password_file;
  std::string ca_file;
  std::string client_id;
  // True when arg is one of them (its value taken).
  bool take(std::string_view arg, const std::string& value);
  // The link's options (url, credentials, CA), the password read from its file; an error naming
  // the option when it cannot be.
  [[nodiscard]] Result<hal::PubSubOptions> options() const;
};
// Decimal, or 0x-prefixed hexadecimal; the whole text, in range.
bool parse_u32(std::string_view text, std::uint32_t& out);
bool parse_u64(std::string_view text, std::uint64_t& out);
// "X,Y" in metres, both finite.
bool parse_point_m(std::string_view text, msg::Point2D& out);
// An LMS200 variant as angle/resolution in degrees ("180/0.5" -> {180, 50}); only the five
// variants the scanner has.
bool parse_lms200_variant(std::string_view text, lms200::Variant& out);

// One command of a binary: `word` (and `second`, for two-word commands such as "decode p2os")
// and the function that takes the arguments after them.
struct Command {
  std::string_view word;
  std::string_view second;  // empty: a one-word command
  int (*run)(int argc, char** argv, std::FILE* out, std::FILE* err);
};

// The top of a binary's command line: --help/-h/help, version/--version (as "program
// version"), then the commands; anything else prints the usage with exit status 2.
int dispatch(int argc, char** argv, std::string_view program, const char* version, const char* usage,
             std::span<const Command> commands, std::FILE* out, std::FILE* err);

// SIGINT/SIGTERM set a flag while this object lives; the previous handlers come back after.
// One at a time per process.
class StopOnSignal {
 public:
  StopOnSignal();
  ~StopOnSignal();
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;

  // The signal that asked to stop, or 0.
  [[nodiscard]] static int requested() noexcept;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace sen3bot::firmware
