#pragma once
// The P2OS VEL packets the base driver writes on the simulated wire, each with what the bus
// held when it was written: the measure of sense-to-act tests.
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/protocol.hpp"
#include "sen3bot/sim/sim_board.hpp"

namespace sen3bot::testing {

// One VEL packet on the wire and what the bus held when it was written.
struct VelPacket {
  hal::Nanos t_ns = 0;
  std::int32_t vel_mm_s = 0;
  tasks::Sample<msg::VelocityCommand> request;
  tasks::Sample<msg::VelocityCommand> command;
  tasks::Sample<msg::SafetyOutput> safety;
  tasks::Sample<msg::ScanMessage> scan;
};

class VelRecorder final : public sim::WireTap {
 public:
  explicit VelRecorder(const firmware::Firmware& fw) : fw_(fw) {}
  void on_write(std::string_view link, std::span<const std::uint8_t> bytes, hal::Nanos now_ns) override {
    if (link != "base") return;
    parser_.feed(bytes, now_ns, [&](const p2os::Frame& frame) {
      if (frame.type != static_cast<std::uint8_t>(p2os::Command::vel)) return;
      VelPacket p;
      p.t_ns = now_ns;
      p.vel_mm_s = p2os::decode_argument(frame.payload).value;
      fw_.request().read(p.request);
      fw_.command().read(p.command);
      fw_.safety_output().read(p.safety);
      fw_.scan().read(p.scan);
      packets.push_back(p);
    });
  }
  std::vector<VelPacket> packets;

 private:
  const firmware::Firmware& fw_;
  p2os::FrameParser parser_;
};

}  // namespace sen3bot::testing
