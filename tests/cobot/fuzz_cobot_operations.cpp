// Fuzz target: any operations file text is a configuration that holds together or an error
// naming the file, never a crash (yaml-cpp's exceptions stay inside parse_operations).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/cobot/operations.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::cobot;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  sen3bot::Result<OperationsConfig> c = parse_operations(text, "fuzz.yaml");
  if (!c) {
    if (std::string_view(c.error().c_str()).find("fuzz.yaml: ") != 0) __builtin_trap();
    return 0;
  }
  if (c->grid.cells() == 0 || c->grid.cells() > kMaxGridCells || !(c->grid.cell_m >= 0.05)) __builtin_trap();
  if (c->operations.size() < 2 || c->operations.size() > kMaxOperations) __builtin_trap();
  for (const Operation& op : c->operations) {
    if (op.stations.size() < 2) __builtin_trap();
    for (const std::size_t s : op.stations)
      if (s >= c->stations.size()) __builtin_trap();
    if (c->find_operation(op.name) < 0) __builtin_trap();
  }
  return 0;
}
