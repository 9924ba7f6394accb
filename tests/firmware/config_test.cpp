#include <gtest/gtest.h>

#include <string>

#include "config.hpp"

namespace sen3bot::firmware {
namespace {

constexpr const char* kValid = R"(
robot: { name: test-bot }
run: { clock: realtime, duration_s: 2.5 }
realtime: { lock_memory: false, prefault_stack_bytes: 128KiB, thread_stack_bytes: 2MiB }
threads:
  control: { cpu: 1 }
  background: { realtime: false }
tasks:
  health: { arena_bytes: 4KiB, stall_periods: 5 }
  telemetry: { arena_bytes: 2048, status_period_s: 0.5 }
)";

std::string message_of(std::string_view yaml) {
  Result<FirmwareConfig> r = parse_config(yaml, "robot.yaml");
  EXPECT_FALSE(r);
  return r ? std::string() : std::string(r.error().message());
}

TEST(Config, ParsesEveryKey) {
  Result<FirmwareConfig> r = parse_config(kValid, "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  const FirmwareConfig& c = *r;
  EXPECT_EQ(c.robot_name, "test-bot");
  EXPECT_EQ(c.clock, ClockMode::realtime);
  EXPECT_DOUBLE_EQ(c.duration_s, 2.5);
  EXPECT_FALSE(c.lock_memory);
  EXPECT_EQ(c.prefault_stack_bytes, 128u * 1024);
  EXPECT_EQ(c.thread_stack_bytes, 2u * 1024 * 1024);
  EXPECT_EQ(c.threads.at("control").cpu, 1);
  EXPECT_TRUE(c.threads.at("control").realtime);
  EXPECT_FALSE(c.threads.at("background").realtime);
  EXPECT_EQ(c.tasks.at("health").arena_bytes, 4096u);
  EXPECT_EQ(c.tasks.at("telemetry").arena_bytes, 2048u);
  EXPECT_EQ(c.health_stall_periods, 5);
  EXPECT_EQ(c.telemetry_status_period_ms, 500);
}

TEST(Config, TheShippedConfigurationsLoad) {
  Result<FirmwareConfig> robot = load_config(SEN3BOT_SOURCE_DIR "/config/robot.yaml");
  EXPECT_TRUE(robot) << (robot ? "" : robot.error().c_str());
  // The simulated robot's section belongs to the simulated board: accepted only when the
  // caller says so, and then left alone.
  const std::string_view board_sections[] = {"sim"};
  Result<FirmwareConfig> sim = load_config(SEN3BOT_SOURCE_DIR "/config/sim.yaml", board_sections);
  EXPECT_TRUE(sim) << (sim ? "" : sim.error().c_str());
  Result<FirmwareConfig> refused = load_config(SEN3BOT_SOURCE_DIR "/config/sim.yaml");
  ASSERT_FALSE(refused);
  EXPECT_NE(std::string(refused.error().message()).find("sim.yaml: sim: a simulated robot: run this configuration with sen3bot-sim"),
            std::string::npos)
      << refused.error().c_str();
}

TEST(Config, BoardIoLines) {
  Result<FirmwareConfig> r = parse_config(std::string(kValid) + "board: { estop_input: /dev/gpiochip0:17, light_output: /dev/gpiochip0:27 }\n",
                                          "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_EQ(r->board.estop_input, "/dev/gpiochip0:17");
  EXPECT_EQ(r->board.light_output, "/dev/gpiochip0:27");
  const std::string m = message_of(std::string(kValid) + "board: { estop: /dev/gpiochip0:17 }\n");
  EXPECT_NE(m.find("board.estop: unknown key"), std::string::npos) << m;
}

TEST(Config, MappingSection) {
  Result<FirmwareConfig> off = parse_config(kValid, "/site/robot.yaml");
  ASSERT_TRUE(off);
  EXPECT_FALSE(off->mapping.enabled);
  Result<FirmwareConfig> r = parse_config(
      std::string(kValid) + "mapping: { out: maps/new.yaml, max_scans: 5000, resolution_m: 0.1, scans_per_submap: 20, "
                            "max_range_m: 15, finished_submap_bytes: 8MiB }\n",
      "/site/robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_TRUE(r->mapping.enabled);
  EXPECT_EQ(r->mapping.task.out_path, "/site/maps/new.yaml");  // beside the configuration
  EXPECT_EQ(r->mapping.task.max_scans, 5000u);
  EXPECT_DOUBLE_EQ(r->mapping.task.mapper.resolution_m, 0.1);
  EXPECT_EQ(r->mapping.task.mapper.scans_per_submap, 20);
  EXPECT_DOUBLE_EQ(r->mapping.task.mapper.max_range_m, 15.0);
  EXPECT_EQ(r->mapping.task.finished_submap_bytes, 8u << 20);
  std::string m = message_of(std::string(kValid) + "mapping: { max_scans: 10 }\n");
  EXPECT_NE(m.find("mapping.out"), std::string::npos) << m;
  m = message_of(std::string(kValid) + "mapping: { out: a.yaml, resolution_m: 0 }\n");
  EXPECT_NE(m.find("mapping.resolution_m"), std::string::npos) << m;
  m = message_of(std::string(kValid) + "mapping: { out: a.yaml, loops: 3 }\n");
  EXPECT_NE(m.find("mapping.loops: unknown key"), std::string::npos) << m;
}

TEST(Config, ErrorsNameTheFileTheKeyAndTheProblem) {
  std::string m = message_of(R"(
robot: { name: x }
run: { clock: lockstep, duration_s: abc }
tasks: { health: { arena_bytes: 1KiB } }
)");
  EXPECT_NE(m.find("robot.yaml: run.duration_s: expected a number, got 'abc' (line 3"), std::string::npos) << m;

  m = message_of(R"(
robot: { name: x }
run: { clock: sometimes, duration_s: 1 }
tasks: {}
)");
  EXPECT_NE(m.find("run.clock: expected 'lockstep' or 'realtime', got 'sometimes'"), std::string::npos) << m;

  m = message_of(R"(
robot: { name: x }
run: { clock: lockstep, duration_s: 1 }
tasks:
  health: { arena_bytes: 4KB }
)");
  EXPECT_NE(m.find("tasks.health.arena_bytes: "), std::string::npos) << m;
  EXPECT_NE(m.find("4KB"), std::string::npos) << m;

  m = message_of(R"(
robot: { name: x }
run: { clock: lockstep, duration_s: 1 }
tasks:
  health: { arena_bytes: 4KiB, stal_periods: 3 }
)");
  EXPECT_NE(m.find("tasks.health.stal_periods: unknown key"), std::string::npos) << m;
  EXPECT_NE(m.find("(line 5"), std::string::npos) << m;

  m = message_of("robot: { name: x }\ntasks: {}\n");
  EXPECT_NE(m.find("robot.yaml: run: missing"), std::string::npos) << m;

  m = message_of("robot: { name: x }\nrun: { clock: lockstep, duration_s: -1 }\ntasks: {}\n");
  EXPECT_NE(m.find("run.duration_s: value -1 is outside"), std::string::npos) << m;

  m = message_of("robot: [1, 2\n");
  EXPECT_NE(m.find("robot.yaml: not valid YAML"), std::string::npos) << m;

  m = message_of("");
  EXPECT_NE(m.find("robot.yaml: the file is empty"), std::string::npos) << m;

  m = message_of("- just\n- a list\n");
  EXPECT_NE(m.find("expected a mapping"), std::string::npos) << m;

  m = message_of(R"(
robot: { name: x }
run: { clock: lockstep, duration_s: 1 }
threads: { control: { cpu: many } }
tasks: {}
)");
  EXPECT_NE(m.find("threads.control.cpu: expected an integer, got 'many'"), std::string::npos) << m;
}

constexpr const char* kNavigation = R"(
robot: { name: x }
run: { clock: lockstep, duration_s: 1 }
tasks: {}
navigation:
  map: maps/lab.yaml
  goals: [[4.0, 7.0]]
)";

TEST(Config, LocalizationRecovery) {
  Result<FirmwareConfig> defaults = parse_config(kNavigation, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_DOUBLE_EQ(defaults->navigation.mcl.recovery_alpha_slow, 0.0);  // off, as AMCL
  EXPECT_DOUBLE_EQ(defaults->navigation.mcl.recovery_alpha_fast, 0.0);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) + "  recovery: { alpha_slow: 0.002, alpha_fast: 0.2, lost_ratio: 0.8, headings: 12 }\n",
      "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_DOUBLE_EQ(r->navigation.mcl.recovery_alpha_slow, 0.002);
  EXPECT_DOUBLE_EQ(r->navigation.mcl.recovery_alpha_fast, 0.2);
  EXPECT_DOUBLE_EQ(r->navigation.mcl.lost_likelihood_ratio, 0.8);
  EXPECT_EQ(r->navigation.mcl.injection_headings, 12u);
  Result<FirmwareConfig> off = parse_config(std::string(kNavigation) + "  recovery: { alpha_slow: 0, alpha_fast: 0 }\n", "robot.yaml");
  ASSERT_TRUE(off) << off.error().c_str();

  std::string m = message_of(std::string(kNavigation) + "  recovery: { alpha_slow: 0.1, alpha_fast: 0.01 }\n");
  EXPECT_NE(m.find("navigation.recovery.alpha_fast: must be larger than alpha_slow"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  recovery: { alpha_fast: 2 }\n");
  EXPECT_NE(m.find("navigation.recovery.alpha_fast: value 2 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  recovery: { alpha: 0.1 }\n");
  EXPECT_NE(m.find("navigation.recovery.alpha: unknown key"), std::string::npos) << m;
}

TEST(Config, DynamicObstaclesMoverPredictionAndTheLocalCostmap) {
  Result<FirmwareConfig> defaults = parse_config(kNavigation, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_TRUE(defaults->navigation.dynamic_obstacles.enabled);  // on unless turned off
  EXPECT_TRUE(defaults->navigation.dwa.mover_prediction);
  EXPECT_DOUBLE_EQ(defaults->navigation.local_costmap_size_m, 6.0);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) +
          "  dynamic_obstacles: { enabled: false, alpha_fast: 0.9, alpha_slow: 0.2, beta: 0.8, c1: 100, c2: 60,\n"
          "    confirm_hits: 5, camera_vouches: true, gate_m: 0.8, max_tracks: 12, front_horizon_s: 0.5, max_speed_m_s: 1.5 }\n"
          "  mover_prediction: { enabled: false, horizon_s: 3, stay_horizon_s: 8, margin_m: 0.2, weight: 2,\n"
          "    brake_delay_s: 0.3, brake_decel_m_s2: 0.4, may_return: false }\n"
          "  local_costmap: { size_m: 8, obstacle_range_m: 3.5, raytrace_range_m: 4, sonar_clearing: false }\n",
      "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  const NavigationSection& n = r->navigation;
  EXPECT_FALSE(n.dynamic_obstacles.enabled);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.detector.alpha_fast, 0.9);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.detector.alpha_slow, 0.2);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.detector.beta, 0.8);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.detector.c1, 100.0);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.detector.c2, 60.0);
  EXPECT_EQ(n.dynamic_obstacles.tracker.confirm_hits, 5);
  EXPECT_TRUE(n.dynamic_obstacles.tracker.camera_vouches);
  EXPECT_FALSE(defaults->navigation.dynamic_obstacles.tracker.camera_vouches);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.tracker.gate_m, 0.8);
  EXPECT_EQ(n.dynamic_obstacles.tracker.max_tracks, 12u);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.cost.front_horizon_s, 0.5);
  EXPECT_DOUBLE_EQ(n.dynamic_obstacles.cost.max_speed_m_s, 1.5);
  EXPECT_FALSE(n.dwa.mover_prediction);
  EXPECT_DOUBLE_EQ(n.dwa.mover_horizon_s, 3.0);
  EXPECT_DOUBLE_EQ(n.dwa.mover_stay_horizon_s, 8.0);
  EXPECT_DOUBLE_EQ(n.dwa.mover_margin_m, 0.2);
  EXPECT_DOUBLE_EQ(n.dwa.mover_weight, 2.0);
  EXPECT_DOUBLE_EQ(n.dwa.mover_brake_delay_s, 0.3);
  EXPECT_DOUBLE_EQ(n.dwa.mover_brake_decel_m_s2, 0.4);
  EXPECT_FALSE(n.dwa.mover_may_return);
  EXPECT_DOUBLE_EQ(n.local_costmap_size_m, 8.0);
  EXPECT_DOUBLE_EQ(n.local_obstacles.obstacle_max_range_m, 3.5);
  EXPECT_DOUBLE_EQ(n.local_obstacles.raytrace_max_range_m, 4.0);
  EXPECT_TRUE(defaults->navigation.local_obstacles.sonar_clearing);
  EXPECT_FALSE(n.local_obstacles.sonar_clearing);

  std::string m = message_of(std::string(kNavigation) + "  dynamic_obstacles: { alpha_fast: 0.2, alpha_slow: 0.3 }\n");
  EXPECT_NE(m.find("navigation.dynamic_obstacles.alpha_slow: must be smaller than alpha_fast"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  dynamic_obstacles: { max_tracks: 40 }\n");
  EXPECT_NE(m.find("navigation.dynamic_obstacles.max_tracks: value 40 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  dynamic_obstacles: { c3: 1 }\n");
  EXPECT_NE(m.find("navigation.dynamic_obstacles.c3: unknown key"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  mover_prediction: { weight: -1 }\n");
  EXPECT_NE(m.find("navigation.mover_prediction.weight: value -1 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  local_costmap: { size_m: 6, obstacle_range_m: 3, raytrace_range_m: 2.5 }\n");
  EXPECT_NE(m.find("navigation.local_costmap.raytrace_range_m: must be at least obstacle_range_m"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  local_costmap: { size_m: 6, obstacle_range_m: 3, raytrace_range_m: 3.5 }\n");
  EXPECT_NE(m.find("navigation.local_costmap.raytrace_range_m: reaches beyond the window"), std::string::npos) << m;
}

TEST(Config, TheSafetyFiltersApproachCheck) {
  Result<FirmwareConfig> defaults = parse_config(kNavigation, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_DOUBLE_EQ(defaults->navigation.safety.approach_horizon_s, 1.0);
  EXPECT_TRUE(defaults->navigation.safety.approach_candidates);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) + "  approach: { horizon_s: 0.8, margin_m: 0.15, min_speed_m_s: 0.4, candidates: false }\n",
      "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_DOUBLE_EQ(r->navigation.safety.approach_horizon_s, 0.8);
  EXPECT_DOUBLE_EQ(r->navigation.safety.approach_margin_m, 0.15);
  EXPECT_DOUBLE_EQ(r->navigation.safety.approach_min_speed_m_s, 0.4);
  EXPECT_FALSE(r->navigation.safety.approach_candidates);
  std::string m = message_of(std::string(kNavigation) + "  approach: { horizon_s: 9 }\n");
  EXPECT_NE(m.find("navigation.approach.horizon_s: value 9 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  approach: { margin: 0.1 }\n");
  EXPECT_NE(m.find("navigation.approach.margin: unknown key"), std::string::npos) << m;
}

TEST(Config, TheCrossingGateAndTheLanes) {
  Result<FirmwareConfig> defaults = parse_config(kNavigation, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_TRUE(defaults->navigation.crossings.enabled);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) +
          "  crossings: { enabled: false, lookahead_m: 3, horizon_s: 5, spread_m_s: 0.2, margin_m: 0.15, go_share: 0.8, "
          "lane_decay_s: 120, lane_band_weight: 0.3 }\n",
      "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_FALSE(r->navigation.crossings.enabled);
  EXPECT_DOUBLE_EQ(r->navigation.crossings.lookahead_m, 3.0);
  EXPECT_DOUBLE_EQ(r->navigation.crossings.horizon_s, 5.0);
  EXPECT_DOUBLE_EQ(r->navigation.crossings.spread_m_s, 0.2);
  EXPECT_DOUBLE_EQ(r->navigation.crossings.margin_m, 0.15);
  EXPECT_DOUBLE_EQ(r->navigation.crossings.go_share, 0.8);
  EXPECT_DOUBLE_EQ(r->navigation.lanes.decay_s, 120.0);
  EXPECT_DOUBLE_EQ(r->navigation.lanes.band_weight, 0.3);
  std::string m = message_of(std::string(kNavigation) + "  crossings: { horizon_s: 30 }\n");
  EXPECT_NE(m.find("navigation.crossings.horizon_s: value 30 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  crossings: { spread: 0.1 }\n");
  EXPECT_NE(m.find("navigation.crossings.spread: unknown key"), std::string::npos) << m;
}

TEST(Config, TheSpeedAndSeparationLimit) {
  Result<FirmwareConfig> defaults = parse_config(kNavigation, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_DOUBLE_EQ(defaults->navigation.safety.separation_spread_m_s, 0.3);
  Result<FirmwareConfig> r = parse_config(std::string(kNavigation) + "  separation: { spread_m_s: 0.5 }\n", "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_DOUBLE_EQ(r->navigation.safety.separation_spread_m_s, 0.5);
  r = parse_config(std::string(kNavigation) + "  separation: { enabled: false }\n", "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_LT(r->navigation.safety.separation_spread_m_s, 0.0);
  std::string m = message_of(std::string(kNavigation) + "  separation: { spread_m_s: -1 }\n");
  EXPECT_NE(m.find("navigation.separation.spread_m_s: value -1 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  separation: { spread: 0.1 }\n");
  EXPECT_NE(m.find("navigation.separation.spread: unknown key"), std::string::npos) << m;
}

TEST(Config, MakingWay) {
  Result<FirmwareConfig> defaults = parse_config(kNavigation, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_FALSE(defaults->navigation.make_way.enabled);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) +
          "  make_way: { enabled: true, horizon_s: 5, forward_m_s: 0.4, reverse_m_s: 0.2, slack_s: 0.8 }\n",
      "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_TRUE(r->navigation.make_way.enabled);
  EXPECT_DOUBLE_EQ(r->navigation.make_way.horizon_s, 5.0);
  EXPECT_DOUBLE_EQ(r->navigation.make_way.forward_m_s, 0.4);
  EXPECT_DOUBLE_EQ(r->navigation.make_way.reverse_m_s, 0.2);
  EXPECT_DOUBLE_EQ(r->navigation.make_way.slack_s, 0.8);
  std::string m = message_of(std::string(kNavigation) + "  make_way: { reverse_m_s: 3 }\n");
  EXPECT_NE(m.find("navigation.make_way.reverse_m_s: value 3 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  make_way: { speed: 0.1 }\n");
  EXPECT_NE(m.find("navigation.make_way.speed: unknown key"), std::string::npos) << m;
}

TEST(Config, TheCollaborativeMode) {
  const std::string people = std::string(kNavigation) + "  people: { detector: sim }\n";
  Result<FirmwareConfig> r = parse_config(
      people +
          "cobot:\n  site: cobot/lab_site.yaml\n  operators: [42, 7]\n  operator_safety_radius_m: 0.3\n"
          "  trigger: { front_min_s: 1.5, max_distance_m: 1.2 }\n  follow: { distance_m: 0.8, goal_step_m: 0.3 }\n"
          "  recognition: { operations: cobot/operations.yaml, model: cobot/m.yaml.gz, rate_hz: 2 }\n",
      "/etc/sen3bot/robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  const CobotSection& c = r->cobot;
  EXPECT_TRUE(c.enabled);
  EXPECT_EQ(c.site_path, "/etc/sen3bot/cobot/lab_site.yaml");
  ASSERT_EQ(c.task.trigger.operators.size(), 2u);
  EXPECT_EQ(c.task.trigger.operators[1], 7u);
  EXPECT_DOUBLE_EQ(c.operator_safety_radius_m, 0.3);
  EXPECT_DOUBLE_EQ(c.task.trigger.front_min_s, 1.5);
  EXPECT_DOUBLE_EQ(c.task.trigger.max_distance_m, 1.2);
  EXPECT_DOUBLE_EQ(c.task.follow.distance_m, 0.8);
  EXPECT_DOUBLE_EQ(c.task.goal_step_m, 0.3);
  EXPECT_TRUE(c.recognition);
  EXPECT_EQ(c.model_path, "/etc/sen3bot/cobot/m.yaml.gz");
  EXPECT_DOUBLE_EQ(c.recognition_rate_hz, 2.0);

  std::string m = message_of(people + "cobot: { site: s.yaml, operators: [] }\n");
  EXPECT_NE(m.find("cobot.operators: expected at least one"), std::string::npos) << m;
  m = message_of(people + "cobot: { site: s.yaml, operators: [0] }\n");
  EXPECT_NE(m.find("cobot"), std::string::npos) << m;
  m = message_of(people + "cobot: { site: s.yaml, operators: [1], trigger: { min_distance_m: 1.5 } }\n");
  EXPECT_NE(m.find("cobot.trigger: each window"), std::string::npos) << m;
  m = message_of(people + "cobot: { site: s.yaml, operators: [1], follow: { speed: 1 } }\n");
  EXPECT_NE(m.find("cobot.follow.speed: unknown key"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "cobot: { site: s.yaml, operators: [1] }\n");
  EXPECT_NE(m.find("needs navigation with navigation.people"), std::string::npos) << m;
}

TEST(Config, TheSafetyFiltersCageCheck) {
  Result<FirmwareConfig> defaults = parse_config(std::string(kNavigation) + "  people: { detector: sim }\n", "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_DOUBLE_EQ(defaults->navigation.safety.cage_margin_m, 0.1);
  EXPECT_TRUE(defaults->navigation.cage_movers);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) + "  people: { detector: sim, keep_out: { margin_m: 0.3, movers: false } }\n", "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_DOUBLE_EQ(r->navigation.safety.cage_margin_m, 0.3);
  EXPECT_FALSE(r->navigation.cage_movers);
  Result<FirmwareConfig> off =
      parse_config(std::string(kNavigation) + "  people: { detector: sim, keep_out: { enabled: false } }\n", "robot.yaml");
  ASSERT_TRUE(off) << off.error().c_str();
  EXPECT_LT(off->navigation.safety.cage_margin_m, 0.0);
  const std::string m = message_of(std::string(kNavigation) + "  people: { detector: sim, keep_out: { horizon_s: 1 } }\n");
  EXPECT_NE(m.find("navigation.people.keep_out.horizon_s: unknown key"), std::string::npos) << m;
}

TEST(Config, TheSafeCurveAndTheSupervisoryPlanner) {
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) +
          "  safe_curve: maps/lab_curve.yaml\n"
          "  sgp: { step_m: 0.01, max_steps: 5000, waypoint_spacing_m: 0.5, barrier_k: 2, zeta: 0.5, on_curve_m: 0.02,\n"
          "    max_waypoints: 100 }\n",
      "/robot/robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  const NavigationSection& n = r->navigation;
  EXPECT_EQ(n.safe_curve_path, "/robot/maps/lab_curve.yaml");
  EXPECT_TRUE(n.waypoints_path.empty());
  EXPECT_DOUBLE_EQ(n.sgp.step_m, 0.01);
  EXPECT_EQ(n.sgp.max_steps, 5000);
  EXPECT_DOUBLE_EQ(n.sgp.waypoint_spacing_m, 0.5);
  EXPECT_DOUBLE_EQ(n.sgp.barrier_k, 2.0);
  EXPECT_DOUBLE_EQ(n.sgp.zeta, 0.5);
  EXPECT_DOUBLE_EQ(n.sgp.on_curve_m, 0.02);
  EXPECT_EQ(n.sgp.max_waypoints, 100u);

  std::string m = message_of(std::string(kNavigation) + "  waypoints: a.txt\n  safe_curve: c.yaml\n");
  EXPECT_NE(m.find("navigation.safe_curve: waypoints and safe_curve are alternatives"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  sgp: { step_m: 0 }\n");
  EXPECT_NE(m.find("navigation.sgp.step_m: value 0 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  sgp: { step_m: 0.2, waypoint_spacing_m: 0.1 }\n");
  EXPECT_NE(m.find("navigation.sgp.waypoint_spacing_m: is shorter than step_m"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  sgp: { zeta_sign: 1 }\n");
  EXPECT_NE(m.find("navigation.sgp.zeta_sign: unknown key"), std::string::npos) << m;
}

TEST(Config, PeopleTheirCagesAndTheOnlineSgp) {
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) +
          "  people:\n"
          "    detector: udp://0.0.0.0:5600\n"
          "    safety_radius_m: 0.6\n"
          "    expire_s: 3\n"
          "    confirm_boxes: 2\n"
          "    laser_follow_s: 5\n"
          "    follow_gate_m: 0.3\n"
          "    max_body_radius_m: 0.2\n"
          "    robot_clearance_m: 0.3\n"
          "    online_sgp: { trigger_distance_m: 1.5, deviation_m: 0.3, delay_s: 0.5, cooldown_s: 4, person_timeout_s: 6 }\n",
      "/robot/robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  const NavigationSection& n = r->navigation;
  EXPECT_TRUE(n.people_enabled);
  EXPECT_EQ(n.people_detector, "udp://0.0.0.0:5600");
  EXPECT_DOUBLE_EQ(n.person_tracker.safety_radius_m, 0.6);
  EXPECT_DOUBLE_EQ(n.person_tracker.expire_s, 3.0);
  EXPECT_DOUBLE_EQ(n.cages.expire_s, 3.0);
  EXPECT_EQ(n.person_tracker.confirm_hits, 2u);
  EXPECT_DOUBLE_EQ(n.person_tracker.laser_follow_s, 5.0);
  EXPECT_DOUBLE_EQ(n.person_tracker.follow_gate_m, 0.3);
  EXPECT_DOUBLE_EQ(n.fusion.max_body_radius_m, 0.2);
  EXPECT_DOUBLE_EQ(n.cages.robot_clearance_m, 0.3);
  EXPECT_TRUE(n.osgp_enabled);
  EXPECT_DOUBLE_EQ(n.osgp.trigger_distance_m, 1.5);
  EXPECT_DOUBLE_EQ(n.osgp.deviation_m, 0.3);
  EXPECT_DOUBLE_EQ(n.osgp.delay_s, 0.5);
  EXPECT_DOUBLE_EQ(n.osgp.cooldown_s, 4.0);
  EXPECT_DOUBLE_EQ(n.osgp.person_timeout_s, 6.0);

  r = parse_config(std::string(kNavigation) +
                       "  people: { detector: onboard, onboard: { rate_hz: 1, scale: 0.75, threshold: 0.5, "
                       "min_height_px: 80 } }\n",
                   "/robot/robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_EQ(r->navigation.people_detector, "onboard");
  EXPECT_DOUBLE_EQ(r->navigation.onboard_rate_hz, 1.0);
  EXPECT_DOUBLE_EQ(r->navigation.onboard_hog.scale, 0.75);
  EXPECT_DOUBLE_EQ(r->navigation.onboard_hog.hit_threshold, 0.5);
  EXPECT_DOUBLE_EQ(r->navigation.onboard_hog.min_height_px, 80.0);

  std::string m = message_of(std::string(kNavigation) + "  people: { detector: sim, confirm_boxes: 0 }\n");
  EXPECT_NE(m.find("navigation.people.confirm_boxes: value 0 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  people: { detector: sim, online_sgp: { enabled: false, delay: 1 } }\n");
  EXPECT_NE(m.find("navigation.people.online_sgp.delay: unknown key"), std::string::npos) << m;
}

TEST(Config, PeopleKeptWhileHidden) {
  Result<FirmwareConfig> defaults = parse_config(std::string(kNavigation) + "  people: { detector: sim }\n", "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_FALSE(defaults->navigation.person_tracker.keep_hidden);
  EXPECT_DOUBLE_EQ(defaults->navigation.person_tracker.hidden_max_s, 30.0);
  Result<FirmwareConfig> r = parse_config(
      std::string(kNavigation) +
          "  people: { detector: sim, hidden: { enabled: true, max_s: 12, max_sigma_m: 1.2, cage_growth_m: 0.3, wander_m2_s: 0.05 } }\n",
      "robot.yaml");
  ASSERT_TRUE(r) << r.error().c_str();
  const nav::PersonTrackerConfig& t = r->navigation.person_tracker;
  EXPECT_TRUE(t.keep_hidden);
  EXPECT_DOUBLE_EQ(t.hidden_max_s, 12.0);
  EXPECT_DOUBLE_EQ(t.hidden_max_sigma_m, 1.2);
  EXPECT_DOUBLE_EQ(t.hidden_cage_growth_m, 0.3);
  EXPECT_DOUBLE_EQ(t.hidden_wander_m2_s, 0.05);
  Result<FirmwareConfig> off =
      parse_config(std::string(kNavigation) + "  people: { detector: sim, hidden: { enabled: false } }\n", "robot.yaml");
  ASSERT_TRUE(off) << off.error().c_str();
  EXPECT_FALSE(off->navigation.person_tracker.keep_hidden);
  std::string m = message_of(std::string(kNavigation) + "  people: { detector: sim, hidden: { max_sigma_m: 0 } }\n");
  EXPECT_NE(m.find("navigation.people.hidden.max_sigma_m: value 0 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  people: { detector: sim, hidden: { cage_growth_m: -0.1 } }\n");
  EXPECT_NE(m.find("navigation.people.hidden.cage_growth_m: value -0.1 is outside"), std::string::npos) << m;
  m = message_of(std::string(kNavigation) + "  people: { detector: sim, hidden: { max_age_s: 5 } }\n");
  EXPECT_NE(m.find("navigation.people.hidden.max_age_s: unknown key"), std::string::npos) << m;
}

TEST(Config, ThreadStacksHoldThePrefault) {
  const std::string minimal = "robot: { name: a }\nrun: { clock: realtime, duration_s: 1 }\ntasks: {}\n";
  Result<FirmwareConfig> defaults = parse_config(minimal, "robot.yaml");
  ASSERT_TRUE(defaults) << defaults.error().c_str();
  EXPECT_EQ(defaults->thread_stack_bytes, 1024u * 1024);
  Result<FirmwareConfig> glibc = parse_config(minimal + "realtime: { thread_stack_bytes: 0 }\n", "robot.yaml");
  ASSERT_TRUE(glibc) << glibc.error().c_str();
  EXPECT_EQ(glibc->thread_stack_bytes, 0u);
  const std::string m =
      message_of(minimal + "realtime: { prefault_stack_bytes: 256KiB, thread_stack_bytes: 256KiB }\n");
  EXPECT_NE(m.find("realtime.thread_stack_bytes: expected 0 or at least"), std::string::npos) << m;
}

TEST(Config, AMissingFileSaysSo) {
  Result<FirmwareConfig> r = load_config("/nonexistent/robot.yaml");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::not_found);
  EXPECT_NE(r.error().message().find("/nonexistent/robot.yaml"), std::string_view::npos);
}

}  // namespace
}  // namespace sen3bot::firmware

namespace sen3bot::firmware {
namespace {

TEST(Config, HostileFilesAreRejectedWithoutCrashing) {
  const std::string nested(5000, '[');
  EXPECT_FALSE(parse_config(nested, "deep.yaml"));
  const std::string path = ::testing::TempDir() + "/huge.yaml";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    const std::string line = "# padding padding padding padding padding padding padding padding\n";
    for (int i = 0; i < 20'000; ++i) std::fputs(line.c_str(), f);
    std::fclose(f);
  }
  Result<FirmwareConfig> r = load_config(path);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message().find("not a configuration file"), std::string_view::npos) << r.error().c_str();
}

}  // namespace
}  // namespace sen3bot::firmware
