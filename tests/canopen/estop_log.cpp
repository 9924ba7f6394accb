#include "estop_log.hpp"

#include <array>
#include <deque>
#include <stdexcept>

#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/candump.hpp"

namespace sen3bot::canopen::estop_log {

namespace {

// The wire at 500 kbit/s: frames go out one after the other, each taking 47 + 8 * dlc bit
// times (stuff bits left out); candump stamps a frame when it has been received, at its end.
struct Wire {
  static constexpr hal::Nanos kBitNs = 2000;
  hal::Nanos free_ns = 0;
  hal::Nanos transmit(const CanFrame& f, hal::Nanos ready_ns) {
    const hal::Nanos start = ready_ns > free_ns ? ready_ns : free_ns;
    free_ns = start + (47 + 8 * static_cast<hal::Nanos>(f.dlc)) * kBitNs;
    return free_ns;
  }
};

// One station's bus handle and the times at which the frames waiting in it were on the wire.
struct Station {
  hal::MemoryCanNode* port = nullptr;
  std::deque<hal::Nanos> stamps;
};

hal::MemoryCanNode* attach(hal::MemoryCanBus& bus, const char* name) {
  Result<hal::MemoryCanNode*> port = bus.attach(name, hal::MemoryCanNodeOptions{256, false});
  if (!port) throw std::runtime_error(port.error().c_str());
  return *port;
}

}  // namespace

std::string make_log() {
  hal::MemoryCanBus bus(3);
  Station master_station{attach(bus, "master"), {}};
  Station node_station{attach(bus, "io-node"), {}};
  Station candump{attach(bus, "candump"), {}};
  Wire wire;

  IoNodeConfig master_config;
  master_config.node = kNode;
  IoNodeMaster master(master_config);
  IoNodeEmulatorConfig node_config;
  node_config.node = kNode;
  IoNodeEmulator node(node_config);
  node.set_inputs(kInputsNormal);

  // Every station but the sender gets the frame (no receive-own), stamped with its time on the wire.
  const auto send = [&](Station& from, const CanFrame& f, hal::Nanos ready_ns) {
    const hal::Nanos stamp = wire.transmit(f, ready_ns);
    if (Status s = from.port->send(f); !s) throw std::runtime_error(s.error().c_str());
    for (Station* s : {&master_station, &node_station, &candump})
      if (s != &from) s->stamps.push_back(stamp);
  };
  // The frames a station received by now_ns, with their times.
  const auto receive = [](Station& at, hal::Nanos now_ns, auto&& handle) {
    while (!at.stamps.empty() && at.stamps.front() <= now_ns) {
      Result<std::optional<CanFrame>> f = at.port->receive();
      if (!f || !*f) throw std::runtime_error("the in-memory bus lost a frame");
      handle(**f, at.stamps.front());
      at.stamps.pop_front();
    }
  };

  std::string log;
  hal::CandumpLine line;
  for (std::size_t i = 0; kInterface[i] != '\0'; ++i) line.interface[i] = kInterface[i];
  std::array<CanFrame, 4> out{};
  // The node runs every 1 ms (a small controller's loop), 0.7 ms into each millisecond; the
  // master every 10 ms, on the millisecond.
  for (hal::Nanos t = 0; t <= kEnd; t += hal::millis(1)) {
    const hal::Nanos now = kStartUnixNs + t;
    if (t % kMasterCycle == 0) {
      receive(master_station, now, [&](const CanFrame& f, hal::Nanos at) { master.on_frame(f, at); });
      master.set_outputs(light_for(master));
      const std::size_t n = master.poll(now, out);
      for (std::size_t i = 0; i < n; ++i) send(master_station, out[i], now + hal::micros(50));
    }
    const hal::Nanos node_now = now + hal::micros(700);
    if (t == kPowerUp) node.power_up(node_now);
    if (t == kPress) node.set_inputs(kInputsPressed);
    if (t == kRelease) node.set_inputs(kInputsNormal);
    if (t == kEmergency) node.raise_emergency(kEmergencyCode, kEmergencyRegister);
    if (t == kUnplug) node.set_silent(true);
    receive(node_station, node_now, [&](const CanFrame& f, hal::Nanos at) { node.on_frame(f, at); });
    const std::size_t k = node.poll(node_now, out);
    for (std::size_t i = 0; i < k; ++i) send(node_station, out[i], node_now + hal::micros(50));
    // candump, listening to everything; what is still on the wire is written next time.
    receive(candump, now + hal::millis(1), [&](const CanFrame& f, hal::Nanos at) {
      line.unix_ns = at;
      line.frame = f;
      std::array<char, hal::kMaxCandumpLine> text{};
      const std::size_t len = hal::format_candump_line(line, text);
      if (len == 0) throw std::runtime_error("a frame candump cannot write");
      log.append(text.data(), len);
    });
  }
  return log;
}

}  // namespace sen3bot::canopen::estop_log
