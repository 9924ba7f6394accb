// Fuzz target: every ONVIF/WS-Discovery reply parser on the same input.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/camera/onvif.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::camera::onvif;
  const std::string_view xml(reinterpret_cast<const char*>(data), size);
  (void)parse_fault(xml);
  (void)parse_system_date_and_time(xml);
  (void)parse_services(xml);
  (void)parse_capabilities(xml);
  if (auto p = parse_profiles(xml)) (void)choose_profile(*p, "H264", 1280, 720);
  (void)parse_media_uri(xml);
  (void)parse_probe_matches(xml);
  (void)parse_duration_s(xml.substr(0, 64));
  return 0;
}
