// canopen_generate_estop_log OUT.log: writes the e-stop scenario's candump log
// (tests/data/can/io_node_estop.log; the scenario is in estop_log.hpp). Regenerate only when
// the master's or the emulator's traffic changes, and commit the result.
#include <cstdio>
#include <exception>
#include <string>

#include "estop_log.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: canopen_generate_estop_log OUT.log\n");
    return 2;
  }
  try {
    const std::string log = sen3bot::canopen::estop_log::make_log();
    std::FILE* f = std::fopen(argv[1], "wb");
    if (f == nullptr || std::fwrite(log.data(), 1, log.size(), f) != log.size() || std::fclose(f) != 0) {
      std::perror(argv[1]);
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "canopen_generate_estop_log: %s\n", e.what());
    return 1;
  }
  return 0;
}
