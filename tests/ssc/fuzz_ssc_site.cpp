// Fuzz target: any bytes as the centre's site file are loaded or refused with an error naming
// the problem, never a crash; a loaded site validates.
#include <cstddef>
#include <cstdint>
#include <string>

#include "sen3bot/ssc/service.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  sen3bot::Result<sen3bot::ssc::SiteFile> site = sen3bot::ssc::parse_site(text, "fuzz.yaml");
  if (!site && site.error().message().empty()) __builtin_trap();
  if (site && !site->site.validate()) __builtin_trap();
  return 0;
}
