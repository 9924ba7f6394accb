#pragma once
// `can io`'s run: one CiA 401 I/O node brought up by the master on a CAN bus, its outputs set,
// one JSON line printed. The robot's command runs it on a SocketCAN interface; the simulator's
// binary on an in-memory bus with the emulated node as the peer.
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::firmware {

struct CanIoOptions {
  std::string iface;
  unsigned node = 0;
  std::uint8_t set_mask = 0;  // outputs named by --set
  std::uint8_t set_values = 0;
  double timeout_s = 3.0;
};

// The other end of an in-process bus: its turn comes each cycle after the master's frames
// went out, so it answers within the same cycle, as a node on a bus would.
class CanIoPeer {
 public:
  virtual ~CanIoPeer() = default;
  virtual void step(hal::Nanos now) = 0;
  // What the peer adds to the result line's object (the "emulator" member).
  virtual void write_json(json::Writer& w) const = 0;
};

// --iface IFACE|sim --node N [--set OUT=0|1 ...] [--timeout S], the node's configuration
// checked; `program` ("sen3bot", "sen3bot-sim") and `usage` go into the messages. 0 or 2.
int parse_can_io(int argc, char** argv, const char* program, const char* usage, CanIoOptions& o, std::FILE* err);
// Runs the master on `bus` until the outputs went out or the timeout: 0, or 1 with the
// master's state and counters on err.
int run_can_io(const CanIoOptions& o, hal::CanBus& bus, CanIoPeer* peer, const char* program, std::FILE* out,
               std::FILE* err);
// "KEY":"0xHH","KEY_on":[1,...]: a byte of eight inputs or outputs, as two members.
void write_can_bits(json::Writer& w, std::string_view key, std::uint8_t bits);

}  // namespace sen3bot::firmware
