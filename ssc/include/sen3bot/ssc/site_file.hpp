#pragma once
// The site file (docs/fleet.md): areas, robots' homes, the centre's thresholds, the service's
// settings. Every key is checked; errors name the file and the key. Read by the centre's
// service and by the robot's collaborative mode (its areas).
#include <string>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/ssc/centre.hpp"
#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::ssc {

struct ServiceConfig {
  std::string interface_name = "uagv";
  vda5050::Version version = vda5050::Version::v2_1_0;
  std::string robot_manufacturer = "Sen3Bot";  // vehicles of this make are the site's robots
  std::string map_id = "map";
  bool direct_pause = false;        // also pause the AGV itself on STOP (VDA 5050 instantActions)
  double advisory_repeat_s = 5.0;   // a standing SLOW or STOP is published again this often
  double step_period_s = 0.05;      // the host's loop: 20 Hz keeps person-to-advisory under 100 ms (docs/fleet-load.md)
};

struct SiteFile {
  Site site;
  CentreConfig centre;
  ServiceConfig service;
  std::vector<std::string> robot_serials;  // index = RobotId
  std::vector<std::string> area_names;     // index = AreaId
};
Result<SiteFile> load_site(const std::string& path);
Result<SiteFile> parse_site(const std::string& yaml_text, const std::string& source_name);

}  // namespace sen3bot::ssc
