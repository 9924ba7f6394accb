// `sen3bot-sim sim --scenario cobot`: the collaborative mode through the whole firmware, the
// camera rendered. Two attempts of each kind: the valid ones toggle every time, the failed
// ones never do and each is refused with its own reason; the operator is followed through the
// work area, the robot stops at its border, goes back to its post and waits again.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sim_commands.hpp"
#include "text_file.hpp"

namespace sen3bot::sim {
namespace {

using sen3bot::testing::read_file;

// The case's object in the report: from its name to the next case's.
std::string case_json(const std::string& json, const std::string& name) {
  const std::size_t at = json.find("{\"name\": \"" + name + "\"");
  if (at == std::string::npos) return "";
  const std::size_t next = json.find("{\"name\": \"", at + 1);
  return json.substr(at, next == std::string::npos ? std::string::npos : next - at);
}

double field(const std::string& json, const std::string& key) { return sen3bot::testing::json_number(json, key); }

TEST(CobotScenario, RequestsToggleFailedAttemptsAreRefusedByReasonAndTheOperatorIsFollowed) {
  char dir_template[] = "/tmp/sen3bot-cobot-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  std::string report = dir_template;
  std::string config = SEN3BOT_SOURCE_DIR "/config/sim.yaml";
  std::vector<char*> argv = {const_cast<char*>("--scenario"), const_cast<char*>("cobot"),
                             const_cast<char*>("--attempts"), const_cast<char*>("2"),
                             const_cast<char*>("--config"), config.data(),
                             const_cast<char*>("--report"), report.data()};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  const int code = sim_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  EXPECT_EQ(code, 0) << "a case failed";
  const std::string json = read_file(report + "/report.json");
  ASSERT_NE(json.find("\"scenario\": \"cobot\""), std::string::npos);

  const std::string collaborate = case_json(json, "collaborate");
  ASSERT_FALSE(collaborate.empty());
  EXPECT_EQ(field(collaborate, "toggles"), 2.0);
  EXPECT_EQ(field(collaborate, "false_toggles"), 0.0);
  EXPECT_GT(field(collaborate, "samples"), 50.0) << "the operator was followed";
  EXPECT_GT(field(collaborate, "min_m"), 0.7) << "never nearer the operator than their cage allows";
  EXPECT_LT(field(collaborate, "mean_m"), 2.0);
  EXPECT_GT(field(collaborate, "border_holds"), 0.0) << "it stopped at the work area's border";
  EXPECT_EQ(field(collaborate, "outside_area_s"), 0.0);
  EXPECT_LT(field(collaborate, "post_error_m"), 0.3) << "back at its post";
  EXPECT_NE(collaborate.find("\"waiting_at_end\": true"), std::string::npos);
  EXPECT_GT(field(collaborate, "worker_path_points"), 20.0);
  EXPECT_EQ(field(collaborate, "moving_contacts"), 0.0);

  const std::string valid = case_json(json, "valid");
  EXPECT_EQ(field(valid, "toggles"), 4.0);
  EXPECT_EQ(field(valid, "false_toggles"), 0.0);

  struct Refused {
    const char* name;
    const char* reason;
  };
  for (const Refused& r : {Refused{"too-far", "too_far"}, Refused{"too-short", "front_too_short"},
                           Refused{"wrong-order", "wrong_order"}, Refused{"unknown-operator", "unknown_operator"},
                           Refused{"person-in-the-way", "person_in_the_way"}}) {
    SCOPED_TRACE(r.name);
    const std::string c = case_json(json, r.name);
    ASSERT_FALSE(c.empty());
    EXPECT_EQ(field(c, "toggles"), 0.0);
    EXPECT_EQ(field(c, "false_toggles"), 0.0);
    EXPECT_EQ(field(c, r.reason), 2.0) << "each attempt refused once, with its reason";
  }
  for (const char* png : {"collaborate", "valid", "too-far"})
    EXPECT_FALSE(read_file(report + "/" + png + ".png").empty()) << png;
}

}  // namespace
}  // namespace sen3bot::sim
