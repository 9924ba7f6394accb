// Fuzz target: any CAN frame through every CANopen decoder gives a value or an error that
// says why, never a crash; what decodes encodes back to the same frame. The same frame then
// goes to the master of an I/O node and to the node's emulator, between their polls.
#include <array>
#include <cstddef>
#include <cstdint>

#include "sen3bot/canopen/codec.hpp"
#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::canopen;
  if (size < 3) return 0;
  CanFrame f;
  f.id = static_cast<std::uint32_t>(data[0] | (data[1] & 0x07) << 8);
  f.rtr = (data[1] & 0x80) != 0;
  f.dlc = static_cast<std::uint8_t>(data[2] % 9);
  for (std::size_t i = 0; i < f.dlc && 3 + i < size; ++i) f.data[i] = data[3 + i];
  const Classified c = classify(f);
  const auto error_said = [](const auto& r) {
    if (!r && r.error().message().empty()) __builtin_trap();
  };
  const auto sdo = decode_sdo(f);
  error_said(sdo);
  if (sdo) {
    if (c.node != sdo->node || sdo->size > 4) __builtin_trap();
    // The same transfer: the command but its reserved bit 4 (accepted either way), the
    // address, and the value's bytes.
    if (sdo->type == SdoType::download_request) {
      const CanFrame again = *sdo_download_request(sdo->node, sdo->at, sdo->value, sdo->size);
      if ((again.data[0] ^ f.data[0]) & ~0x10 || again.data[1] != f.data[1] || again.data[2] != f.data[2] ||
          again.data[3] != f.data[3])
        __builtin_trap();
      for (std::size_t i = 0; i < sdo->size; ++i)
        if (again.data[4 + i] != f.data[4 + i]) __builtin_trap();
    }
  }
  const auto hb = decode_heartbeat(f);
  error_said(hb);
  if (hb && f.dlc == 1 && !hb->toggle && !(heartbeat(hb->node, hb->state).value() == f)) __builtin_trap();
  const auto nmt_command = decode_nmt(f);
  error_said(nmt_command);
  if (nmt_command && f.dlc == 2 && !(nmt(nmt_command->command, nmt_command->node).value() == f)) __builtin_trap();
  const auto emcy = decode_emergency(f);
  error_said(emcy);
  if (emcy && f.dlc == 8 && !(emergency(c.node, *emcy).value() == f)) __builtin_trap();
  (void)describe_emergency(emcy ? emcy->code : 0);
  (void)describe_abort(sdo ? sdo->value : 0);

  IoNodeMaster master(IoNodeConfig{});
  IoNodeEmulator node(IoNodeEmulatorConfig{});
  node.power_up(0);
  std::array<CanFrame, 4> out{};
  for (sen3bot::hal::Nanos t = 10'000'000; t <= 200'000'000; t += 10'000'000) {
    for (std::size_t i = 0, k = master.poll(t, out); i < k; ++i) node.on_frame(out[i], t);
    for (std::size_t i = 0, k = node.poll(t, out); i < k; ++i) master.on_frame(out[i], t);
    master.on_frame(f, t);
    node.on_frame(f, t);
  }
  if (master.inputs_valid() && master.state() != IoNodeState::operational) __builtin_trap();
  return 0;
}
