// `sen3bot-sim can io --iface sim`: the robot's `can io` against the emulated CiA 401 node on
// an in-memory bus, for a demonstration and a test of the command. --sim-inputs sets the
// node's inputs; --sim-silent makes it a node that never answers.
#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "can_io.hpp"
#include "cli_util.hpp"
#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

namespace {

constexpr const char* kUsage =
    "usage: sen3bot-sim can io --iface sim --node N [--set OUT=0|1 ...] [--timeout S]\n"
    "                          [--sim-inputs 0xHH] [--sim-silent]\n";

// The emulated node on its station of the in-memory bus.
class EmulatedNode final : public firmware::CanIoPeer {
 public:
  EmulatedNode(hal::MemoryCanNode& port, const canopen::IoNodeEmulatorConfig& config, std::uint8_t inputs, bool silent)
      : port_(port), emulator_(config) {
    emulator_.set_inputs(inputs);
    emulator_.set_silent(silent);
    emulator_.power_up(hal::PosixClock{}.now());
  }

  void step(hal::Nanos now) override {
    for (;;) {
      Result<std::optional<hal::CanFrame>> r = port_.receive();
      if (!r || !*r) break;
      emulator_.on_frame(**r, now);
    }
    std::array<hal::CanFrame, 4> frames{};
    const std::size_t k = emulator_.poll(now, frames);
    for (std::size_t i = 0; i < k; ++i) (void)port_.send(frames[i]);
  }

  // What the emulated node itself now has: the outputs arrived, not only went out.
  void write_json(json::Writer& w) const override {
    w.key("emulator").begin_object().member("state", canopen::to_string(emulator_.state()));
    firmware::write_can_bits(w, "outputs", emulator_.outputs());
    w.end_object();
  }

 private:
  hal::MemoryCanNode& port_;
  canopen::IoNodeEmulator emulator_;
};

}  // namespace

int can_io_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  // The emulated node's options first; the rest are the robot's.
  std::vector<char*> rest;
  bool inputs_given = false;
  std::uint8_t inputs = 0;
  bool silent = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--sim-silent") {
      silent = true;
    } else if (arg == "--sim-inputs") {
      std::uint32_t number = 0;
      if (i + 1 >= argc) {
        std::fprintf(err, "sen3bot-sim can io: %s needs a value\n%s", argv[i], kUsage);
        return 2;
      }
      if (!firmware::parse_u32(argv[++i], number) || number > 0xFF) {
        std::fprintf(err, "sen3bot-sim can io: bad value '%s' for %s\n%s", argv[i], argv[i - 1], kUsage);
        return 2;
      }
      inputs = static_cast<std::uint8_t>(number);
      inputs_given = true;
    } else {
      rest.push_back(argv[i]);
      if (i + 1 < argc) rest.push_back(argv[++i]);  // its value, whatever it looks like
    }
  }
  firmware::CanIoOptions o;
  if (int rc = firmware::parse_can_io(static_cast<int>(rest.size()), rest.data(), "sen3bot-sim", kUsage, o, err);
      rc != 0)
    return rc;
  if (o.iface != "sim") {
    if (inputs_given || silent)
      std::fprintf(err, "sen3bot-sim can io: --sim-inputs and --sim-silent are for the emulated node: "
                        "only with --iface sim\n");
    else
      std::fprintf(err, "sen3bot-sim can io: --iface sim only (a SocketCAN interface: sen3bot can io)\n");
    return 2;
  }

  hal::MemoryCanBus bus(2);
  Result<hal::MemoryCanNode*> master_port = bus.attach("sim");
  Result<hal::MemoryCanNode*> emulated = bus.attach("io-node");
  if (!master_port || !emulated) {
    std::fprintf(err, "sen3bot-sim can io: sim: %s\n", (!master_port ? master_port : emulated).error().c_str());
    return 1;
  }
  canopen::IoNodeEmulatorConfig node_config;
  node_config.node = static_cast<std::uint8_t>(o.node);
  EmulatedNode node(**emulated, node_config, inputs, silent);
  return firmware::run_can_io(o, **master_port, &node, "sen3bot-sim", out, err);
}

}  // namespace sen3bot::sim
