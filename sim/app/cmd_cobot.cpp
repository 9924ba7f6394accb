// `sen3bot-sim sim --scenario cobot`: the collaborative mode end to end. A robot waits at its
// post in the lab's work area (a type-2 area of config/cobot/lab_site.yaml); scripted operators
// walk up and show the tags of their leg bands to its camera, which the simulation renders; the
// whole firmware (the QR row, the people's fusion, the trigger, the mode, follow-me, the
// planner) answers. One case follows an operator through the area to its border and back;
// the others repeat valid requests or each kind of failed attempt. Each case is its own
// firmware run in lockstep time; the report gives per case the toggles, the false toggles, the
// refusals by reason and the follow distances.
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "case_run.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "report_figure.hpp"
#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/polygon.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/sim/cobot/operator.hpp"
#include "sen3bot/sim/cobot/sim_camera.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

namespace {

using ::sen3bot::cobot::TriggerRejection;
using cobot::AttemptKind;
using cobot::AttemptPlan;
using cobot::OperatorScript;
using firmware::Firmware;
using firmware::FirmwareConfig;

constexpr std::uint32_t kOperator = 42;
constexpr std::uint32_t kSecondOperator = 7;
constexpr std::uint32_t kUnknownOperator = 913;
constexpr double kPersonSizeM = 0.45;
const nav::Pose2D kPost{2.5, 2.2, 0.0};
// Out of the laser's and the camera's view from the post: behind the robot.
constexpr nav::Point2D kOperatorPark{1.8, 3.9};
constexpr nav::Point2D kBystanderPark{1.8, 0.5};
constexpr double kFirstAttemptS = 6.0;  // after the mission's goal (the post) and wait4col
constexpr hal::Nanos kSliceNs = hal::millis(50);
constexpr double kLeadingM_s = 0.45;
// The work area of config/cobot/lab_site.yaml, which follow-me must not leave.
const std::array<msg::Point2D, 4> kAssembly = {{{1.5, 0.2}, {7.8, 0.2}, {7.8, 4.6}, {1.5, 4.6}}};

enum class CaseKind : std::uint8_t { collaborate, requests };

struct CobotCase {
  const char* name;
  const char* description;
  CaseKind kind;
  AttemptKind attempt;
};

const std::array<CobotCase, 7> kCases = {{
    {"collaborate",
     "operator 42 switches the waiting robot to collaborative, walks through the work area and out of its door: the "
     "robot follows 1 m behind and stops at the area's border; the operator comes back and switches it back: the "
     "robot returns to its post and waits again",
     CaseKind::collaborate, AttemptKind::valid},
    {"valid", "operator 42 or 7 asks and asks back, again and again: every request toggles", CaseKind::requests,
     AttemptKind::valid},
    {"too-far", "the sequence shown with the legs 1.2-1.4 m from the laser: refused, never toggles", CaseKind::requests,
     AttemptKind::too_far},
    {"too-short", "the front tag shown for about 1.1-1.7 s only (0.6-1.2 s standing): refused", CaseKind::requests, AttemptKind::too_short},
    {"wrong-order", "the back tag first, then the front: refused", CaseKind::requests, AttemptKind::wrong_order},
    {"unknown-operator", "tags of operator 913, not on the robot's list: refused", CaseKind::requests,
     AttemptKind::unknown_operator},
    {"person-in-the-way", "a valid sequence with a second person standing a step behind the operator: refused",
     CaseKind::requests,
     AttemptKind::person_in_the_way},
}};

struct FollowStats {
  std::size_t samples = 0;
  double min_m = 0, mean_m = 0, max_m = 0;
  void add(double d) {
    min_m = samples == 0 ? d : std::min(min_m, d);
    max_m = samples == 0 ? d : std::max(max_m, d);
    mean_m += (d - mean_m) / static_cast<double>(++samples);
  }
};

struct CaseOutcome {
  std::string name;
  std::string description;
  CaseKind kind = CaseKind::requests;
  std::size_t attempts = 0;
  std::uint32_t toggles_on = 0;
  std::uint32_t toggles_off = 0;
  std::uint32_t expected_toggles = 0;
  std::uint32_t false_toggles = 0;
  std::array<std::uint32_t, ::sen3bot::cobot::kTriggerRejectionCount> rejections{};
  std::uint32_t not_the_operator = 0;
  std::uint32_t wait4col_entries = 0;
  FollowStats follow;            // robot to operator while following a walking operator (truth)
  std::uint32_t border_holds = 0;
  std::uint32_t follow_goals = 0;
  double outside_area_s = 0;     // collaborative with the robot's centre outside the work area
  double post_error_m = -1;      // at the end, from the post (-1: not checked)
  bool waiting_at_end = false;
  std::uint64_t contacts = 0;
  std::uint64_t moving_contacts = 0;
  std::uint64_t frames_rendered = 0;
  std::uint64_t frames_searched = 0;
  std::uint64_t tags_read = 0;
  std::size_t worker_path_points = 0;
  // The operation recognised from the path recorded while following (the last estimate).
  std::string operation;
  double operation_probability = 0;
  std::uint16_t operation_points = 0;
  double sim_s = 0;
  double wall_s = 0;
  bool passed = false;
  std::vector<tasks::TaskStats> stats;
};

// Passes a script's keyframes written since the last call to the world.
struct ScriptFeed {
  std::size_t mover = 0;
  std::size_t pushed = 1;  // the first keyframe is the mover's own
  void push(const OperatorScript& script, world::World& world) {
    for (; pushed < script.keyframes(); ++pushed)
      world.extend_timeline(mover, script.keyframe_at(pushed), script.keyframe_time(pushed));
  }
};

nav::Pose2D laser_pose(const nav::Pose2D& robot, const nav::Pose2D& mount) {
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  return {robot.x_m + c * mount.x_m - s * mount.y_m, robot.y_m + s * mount.x_m + c * mount.y_m,
          nav::normalize_angle(robot.theta_rad + mount.theta_rad)};
}

// Refusals for any reason: the trigger's and the mode's.
std::uint32_t refusals(const CaseOutcome& c) {
  std::uint32_t refused = c.not_the_operator;
  for (const std::uint32_t r : c.rejections) refused += r;
  return refused;
}

bool check(const CaseOutcome& c) {
  const std::uint32_t refused = refusals(c);
  const bool toggles_right = c.toggles_on + c.toggles_off == c.expected_toggles && c.false_toggles == 0;
  if (c.kind == CaseKind::collaborate)
    return toggles_right && c.follow.samples > 0 && c.border_holds > 0 && c.outside_area_s == 0 && c.post_error_m >= 0 &&
           c.post_error_m < 0.3 && c.waiting_at_end && c.moving_contacts == 0;
  if (c.expected_toggles > 0) return toggles_right && c.moving_contacts == 0;
  // Never a toggle; nearly every attempt refused with a reason (one the camera did not read
  // well enough to see as an attempt is not refused, and not taken either).
  return toggles_right && 10 * refused >= 9 * c.attempts && c.moving_contacts == 0;
}

// The case's firmware: the post its one goal, people and moving obstacles on and, unless the
// configuration has its own, the collaborative mode on the lab's site.
FirmwareConfig case_config(const FirmwareConfig& base, const std::string& folder) {
  FirmwareConfig config = base;
  config.clock = firmware::ClockMode::lockstep;
  config.navigation.mcl.initial_pose = kPost;
  config.navigation.mission.goal_count = 1;
  config.navigation.mission.goals[0] = {kPost.x_m, kPost.y_m};
  config.navigation.people_enabled = true;
  config.navigation.people_detector = "sim";
  config.navigation.dynamic_obstacles.enabled = true;
  config.tasks["detector"].arena_bytes = 4 * 1024;
  config.tasks["people"].arena_bytes = 64 * 1024;
  config.tasks["cobot"].arena_bytes = 64 * 1024;
  config.tasks["qr"].arena_bytes = 1024;
  config.tasks["recognition"].arena_bytes = 1024;
  if (!config.cobot.enabled) {
    config.cobot.enabled = true;
    config.cobot.site_path = folder + "cobot/lab_site.yaml";
    config.cobot.task.trigger.operators.clear();
    for (const std::uint32_t id : {kOperator, kSecondOperator}) (void)config.cobot.task.trigger.operators.push_back(id);
    config.cobot.recognition = true;
    config.cobot.operations_path = folder + "cobot/operations.yaml";
    config.cobot.model_path = folder + "cobot/operations-model.yaml.gz";
  }
  return config;
}

// The operations' names for the report, read as the recognition row reads them (none without
// recognition).
Result<std::vector<std::string>> operation_names(const FirmwareConfig& config) {
  std::vector<std::string> names;
  if (!config.cobot.recognition) return names;
  Result<sen3bot::cobot::OperationsConfig> operations = sen3bot::cobot::load_operations(config.cobot.operations_path);
  if (!operations) return operations.error();
  for (const sen3bot::cobot::Operation& o : operations->operations) names.push_back(o.name);
  return names;
}

// The operator and a bystander, parked out of the robot's view until the director sends them.
struct CaseScripts {
  OperatorScript op, bystander;
  CaseScripts() {
    op.start(0.0, kOperatorPark, 0.0);
    bystander.start(0.0, kBystanderPark, 0.0);
  }
};

// What the director sees of a slice.
struct SliceView {
  double sim_s = 0;
  nav::Pose2D laser;
  double standing_since_s = -1;  // -1: the robot moves
  bool standing = false;
  bool waiting = false;  // the robot is in wait4col
};

enum class Stage : std::uint8_t { asking, following, stepping_in, coming_back, returning, done };

// The director: attempts one after another, each planned where the robot is when it starts;
// in the collaborate case then the walk the robot follows, and the operator's way back to
// switch it back.
class Director {
 public:
  Director(const CobotCase& spec, std::size_t planned_attempts, CaseScripts& scripts, world::World& world,
           std::uint64_t seed)
      : spec_(spec), planned_(planned_attempts), op_(scripts.op), bystander_(scripts.bystander), world_(world), rng_(seed) {}

  void step(const SliceView& v) {
    switch (stage_) {
      case Stage::asking: ask(v); break;
      case Stage::following:
        // Back once the robot has stood at the border a while: up to it first, then, once it
        // stands again, into its camera's view to ask back.
        if (stood(v, 1.5)) step_up(v.laser);
        break;
      case Stage::stepping_in:
        if (stood(v, 1.0)) ask_back(v.laser);
        break;
      case Stage::coming_back:
        if (v.sim_s > op_.end_s()) stage_ = Stage::returning;
        break;
      case Stage::returning:
        if (v.waiting && v.standing) stage_ = Stage::done;
        break;
      case Stage::done: break;
    }
  }

  [[nodiscard]] bool done() const noexcept { return stage_ == Stage::done; }
  [[nodiscard]] bool following() const noexcept { return stage_ == Stage::following; }
  [[nodiscard]] std::size_t attempts() const noexcept { return plans_.size(); }
  [[nodiscard]] std::size_t planned() const noexcept { return planned_; }
  [[nodiscard]] std::uint32_t wearing() const noexcept { return wearing_; }  // whose tags the operator shows
  [[nodiscard]] const OperatorScript& op() const noexcept { return op_; }

 private:
  // The operator has finished the script and the robot has stood for more than stood_s.
  [[nodiscard]] bool stood(const SliceView& v, double stood_s) const {
    return v.sim_s > op_.end_s() && v.standing_since_s >= 0 && v.sim_s - v.standing_since_s > stood_s;
  }

  void ask(const SliceView& v) {
    if (plans_.size() < planned_) {
      const double t0 = plans_.empty() ? kFirstAttemptS : op_.end_s() + 1.0;
      if (v.sim_s + 0.5 >= t0) plan_next(std::max(t0, v.sim_s + 0.5), v.laser);
    } else if (spec_.kind == CaseKind::collaborate) {
      lead_out();
    } else if (v.sim_s > op_.end_s() + 3.0) {
      stage_ = Stage::done;
    }
  }

  void plan_next(double t0_s, const nav::Pose2D& laser) {
    AttemptKind kind = spec_.attempt;
    std::uint32_t id = plans_.size() % 2 == 0 ? kOperator : kSecondOperator;
    if (kind == AttemptKind::unknown_operator) id = kUnknownOperator;
    cobot::AttemptOptions o = options_;
    o.twice = spec_.kind == CaseKind::requests && kind == AttemptKind::valid;
    o.leave = spec_.kind != CaseKind::collaborate;
    const AttemptPlan plan = cobot::plan_attempt(op_, kind, id, laser, t0_s, o, rng_);
    wearing_ = id;
    if (plan.bystander) {
      // In place when the operator arrives, gone when they leave.
      const nav::Point2D side{plan.bystander_at.x_m, plan.bystander_at.y_m + (plan.bystander_at.y_m > laser.y_m ? 1.2 : -1.2)};
      bystander_.stand(std::max(0.0, plan.start_s - bystander_.end_s()));
      bystander_.walk_to(side, 2.0);
      bystander_.walk_to(plan.bystander_at, 0.8);
      bystander_.stand(std::max(0.0, plan.end_s - bystander_.end_s() - 1.5));
      bystander_.walk_to(side, 0.8);
      bystander_.walk_to(kBystanderPark, 2.0);
      bystander_feed_.push(bystander_, world_);
    }
    op_feed_.push(op_, world_);
    plans_.push_back(plan);
  }

  // Through the work area and out of its door into the storage area, leading the robot at a
  // pace it can keep (config/sim.yaml: 0.5 m/s at most): round the workstation's north side,
  // west under the pillar, through the door.
  void lead_out() {
    op_.walk_to({4.3, 2.9}, kLeadingM_s);
    op_.walk_to({4.3, 3.9}, kLeadingM_s);
    op_.walk_to({2.9, 4.1}, kLeadingM_s);
    op_.walk_to({2.9, 5.6}, kLeadingM_s);
    op_.walk_to({2.9, 6.4}, kLeadingM_s);
    op_.stand(2.0);
    op_feed_.push(op_, world_);
    stage_ = Stage::following;
  }

  void step_up(const nav::Pose2D& laser) {
    const double c = std::cos(laser.theta_rad), s = std::sin(laser.theta_rad);
    op_.walk_to({laser.x_m + 1.4 * c, laser.y_m + 1.4 * s}, 0.6);
    op_.stand(0.5);
    op_feed_.push(op_, world_);
    stage_ = Stage::stepping_in;
  }

  void ask_back(const nav::Pose2D& laser) {
    const double c = std::cos(laser.theta_rad), s = std::sin(laser.theta_rad);
    const nav::Point2D stand{laser.x_m + 0.95 * c, laser.y_m + 0.95 * s};
    op_.walk_to(stand, 0.4);
    const double face = std::atan2(laser.y_m - stand.y_m, laser.x_m - stand.x_m);
    op_.turn_to(face, 0.8);
    op_.stand(2.1);
    op_.turn_to(face + std::numbers::pi, 0.8);
    op_.stand(2.1);
    op_.walk_to({2.9, 6.6}, 0.9);
    op_feed_.push(op_, world_);
    stage_ = Stage::coming_back;
  }

  const CobotCase& spec_;
  std::size_t planned_;
  OperatorScript& op_;
  OperatorScript& bystander_;
  world::World& world_;
  ScriptFeed op_feed_{0}, bystander_feed_{1};
  std::mt19937_64 rng_;
  cobot::AttemptOptions options_;
  std::vector<AttemptPlan> plans_;
  std::uint32_t wearing_ = kOperator;
  Stage stage_ = Stage::asking;
};

// A slice's measures: time outside the work area while collaborative; while following, the
// newest operation estimate and how far behind the walking operator the robot keeps (truth).
void measure(CaseOutcome& result, const Firmware& fw, const std::vector<std::string>& operation_names,
             const GroundTruth& truth, const world::World& w, const OperatorScript& op, double sim_s, bool collaborative,
             bool following) {
  if (collaborative && !::sen3bot::cobot::inside_polygon(kAssembly, {truth.pose.x_m, truth.pose.y_m}))
    result.outside_area_s += hal::to_seconds(kSliceNs);
  if (!collaborative || !following) return;
  if (tasks::Sample<msg::OperationEstimate> estimate; fw.operation().read(estimate) && estimate.value.best >= 0) {
    const auto best = static_cast<std::size_t>(estimate.value.best);
    if (best < operation_names.size()) result.operation = operation_names[best];
    result.operation_probability = estimate.value.probability[best];
    result.operation_points = estimate.value.points;
  }
  // The operator leading the robot: how far behind it keeps.
  const nav::Point2D a = op.at(sim_s - 0.05), b = op.at(sim_s + 0.05);
  if (std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) / 0.1 > 0.3) {
    const nav::Point2D o = w.mover_position(0);
    result.follow.add(std::hypot(o.x_m - truth.pose.x_m, o.y_m - truth.pose.y_m));
  }
}

// The case's parts while it runs.
struct CaseRig {
  const CobotCase& spec;
  Firmware& fw;
  SimBoard& board;
  cobot::SimCamera& camera;
  Director& director;
  const std::vector<std::string>& operation_names;
  nav::Pose2D mount;  // the laser's, on the robot
};

// The case in lockstep slices until the director is done or the time is up; sim_s the
// simulated time it ran.
Status run_slices(CaseRig& rig, double limit_s, CaseOutcome& result, double& sim_s, std::FILE* out) {
  tasks::Scheduler& scheduler = rig.fw.scheduler();
  hal::SimClock& clock = *rig.board.lockstep_clock();
  world::World& w = rig.board.simulation().world();
  Director& director = rig.director;
  double standing_since_s = -1;
  double next_progress_s = 0;
  while (sim_s < limit_s && !director.done()) {
    if (Status s = scheduler.run_lockstep(clock, kSliceNs); !s) return s;
    sim_s = hal::to_seconds(clock.now() - scheduler.start_time_ns());
    const GroundTruth& truth = rig.board.simulation().truth();
    const nav::Pose2D laser = laser_pose(truth.pose, rig.mount);
    // The camera sees the operator's leg band.
    const cobot::TagWearer wearer{w.mover_position(0), director.op().facing(sim_s), director.wearing()};
    rig.camera.step(clock.now(), laser, std::span(&wearer, 1));

    tasks::Sample<msg::CobotState> state;
    const bool have_state = rig.fw.cobot_state().read(state);
    const bool collaborative = have_state && state.value.mode == msg::CobotMode::collaborative;
    const bool standing = std::fabs(truth.speed_m_s) < 0.01;
    standing_since_s = standing ? (standing_since_s < 0 ? sim_s : standing_since_s) : -1;
    measure(result, rig.fw, rig.operation_names, truth, w, director.op(), sim_s, collaborative, director.following());
    director.step({sim_s, laser, standing_since_s, standing, have_state && state.value.mode == msg::CobotMode::wait4col});
    if (sim_s >= next_progress_s) {
      std::fprintf(out, "  %-18s t=%6.1f s  robot (%5.2f, %5.2f) m  %-13s toggles %u  refusals %u  attempts %zu/%zu\n",
                   rig.spec.name, sim_s, truth.pose.x_m, truth.pose.y_m,
                   have_state ? msg::to_string(state.value.mode) : "-", have_state ? state.value.toggles : 0,
                   have_state ? state.value.rejections : 0, director.attempts(), director.planned());
      std::fflush(out);
      next_progress_s += 10.0;
    }
  }
  return Status::success();
}

// After the run: the cobot task's counters, the truth at the end, the camera's and the QR row's.
void collect(CaseOutcome& result, const CobotCase& spec, const Firmware& fw, SimBoard& board, const cobot::SimCamera& camera) {
  const firmware::CobotTask& task = *fw.cobot();
  result.toggles_on = task.counters().toggles_on;
  result.toggles_off = task.counters().toggles_off;
  result.wait4col_entries = task.counters().wait4col_entries;
  result.border_holds = task.counters().border_holds;
  result.follow_goals = task.counters().follow_goals;
  for (std::size_t r = 0; r < result.rejections.size(); ++r)
    result.rejections[r] = task.trigger().rejections(static_cast<TriggerRejection>(r));
  result.not_the_operator = task.mode().refusals(::sen3bot::cobot::ModeRefusal::not_the_operator);
  const bool asks = spec.attempt == AttemptKind::valid;
  result.expected_toggles =
      !asks ? 0 : spec.kind == CaseKind::collaborate ? 2 : 2 * static_cast<std::uint32_t>(result.attempts);
  const std::uint32_t toggles = result.toggles_on + result.toggles_off;
  result.false_toggles = toggles > result.expected_toggles ? toggles - result.expected_toggles : 0;
  const GroundTruth& truth = board.simulation().truth();
  result.post_error_m = std::hypot(truth.pose.x_m - kPost.x_m, truth.pose.y_m - kPost.y_m);
  tasks::Sample<msg::CobotState> state;
  result.waiting_at_end = fw.cobot_state().read(state) && state.value.mode == msg::CobotMode::wait4col;
  result.contacts = board.referee().report().contacts;
  result.moving_contacts = board.referee().report().moving_contacts;
  result.frames_rendered = camera.frames_rendered();
  if (tasks::Sample<msg::TagFrame> tags; fw.tags().read(tags)) {
    result.frames_searched = tags.value.frames_searched;
    result.tags_read = tags.value.tags_read;
  }
  result.worker_path_points = task.recorder().size();
}

void print_outcome(std::FILE* out, const CaseOutcome& result) {
  const std::uint32_t toggles = result.toggles_on + result.toggles_off;
  std::fprintf(out, "  %s: %zu attempt%s, %u toggle%s (%u expected, %u false), %u refused", result.name.c_str(),
               result.attempts, result.attempts == 1 ? "" : "s", toggles, toggles == 1 ? "" : "s", result.expected_toggles,
               result.false_toggles, refusals(result));
  for (std::size_t r = 0; r < result.rejections.size(); ++r)
    if (result.rejections[r] > 0)
      std::fprintf(out, " %s=%u", ::sen3bot::cobot::to_string(static_cast<TriggerRejection>(r)), result.rejections[r]);
  std::fprintf(out, "\n");
  if (result.follow.samples > 0)
    std::fprintf(out, "  following: %zu samples, robot to operator %.2f / %.2f / %.2f m (min / mean / max), %u goals, "
                 "%u cycles held at the border, %.1f s outside the area\n",
                 result.follow.samples, result.follow.min_m, result.follow.mean_m, result.follow.max_m, result.follow_goals,
                 result.border_holds, result.outside_area_s);
  if (!result.operation.empty())
    std::fprintf(out, "  operation estimate from the %u path points recorded while following (this walk is none of the "
                 "configured operations): %s (p = %.3f)\n",
                 result.operation_points, result.operation.c_str(), result.operation_probability);
  std::fprintf(out, "  qr: %llu frames rendered, %llu searched, %llu tags read; %s (%.0f s simulated in %.1f s)\n",
               static_cast<unsigned long long>(result.frames_rendered),
               static_cast<unsigned long long>(result.frames_searched), static_cast<unsigned long long>(result.tags_read),
               result.passed ? "passed" : "FAILED", result.sim_s, result.wall_s);
}

void write_case_figure(const std::string& report_dir, const CobotCase& spec, std::size_t index, const CaseOutcome& result,
                       const FirmwareConfig& config, const Firmware& fw, SimBoard& board, std::FILE* err) {
  const std::string png = report_dir + "/" + result.name + ".png";
  figure::CaseFigure figure =
      case_figure("case " + std::to_string(index + 1) + "/" + std::to_string(kCases.size()) + ": " + result.name,
                  std::string("cobot: ") + spec.description, config, fw, board);
  figure.goals = {{kPost.x_m, kPost.y_m}};
  figure.result = std::to_string(result.toggles_on + result.toggles_off) + " toggles (" +
                  std::to_string(result.expected_toggles) + " expected), " + std::to_string(refusals(result)) +
                  " refused, " + std::to_string(result.moving_contacts) + " contacts";
  figure.passed = result.passed;
  if (!draw_case_figure(figure).write_png(png)) std::fprintf(err, "sen3bot-sim sim: cannot write %s\n", png.c_str());
}

int run_cobot_case(const CobotCase& spec, std::size_t index, const FirmwareConfig& base, const SimulationConfig& base_world,
                   const std::string& folder, std::size_t attempts, std::uint64_t seed, const std::string& report_dir,
                   CaseOutcome& result, std::FILE* out, std::FILE* err) {
  result.name = spec.name;
  result.description = spec.description;
  result.kind = spec.kind;
  const FirmwareConfig config = case_config(base, folder);
  const Result<std::vector<std::string>> names = operation_names(config);
  if (!names) {
    std::fprintf(err, "sen3bot-sim sim: %s: %s\n", spec.name, names.error().c_str());
    return 1;
  }

  SimulationConfig world = base_world;
  world.start_pose = kPost;
  world.seed = seed + index;
  world.detector.enabled = true;
  CaseScripts scripts;
  world.movers = {scripts.op.mover(kPersonSizeM), scripts.bystander.mover(kPersonSizeM)};

  Result<std::unique_ptr<SimBoard>> created = SimBoard::create(world, true);
  if (!created) {
    std::fprintf(err, "sen3bot-sim sim: %s: %s\n", spec.name, created.error().c_str());
    return 1;
  }
  SimBoard& board = **created;
  cobot::SimCameraConfig camera_config;
  camera_config.camera = nav::CameraCalibration{};
  Result<std::unique_ptr<cobot::SimCamera>> camera = cobot::SimCamera::create(camera_config, seed * 7919 + index);
  if (!camera) {
    std::fprintf(err, "sen3bot-sim sim: %s: %s\n", spec.name, camera.error().c_str());
    return 1;
  }
  const QuietLog quiet(out);
  Firmware fw(config, board, quiet.file());
  fw.use_camera_frames(&(*camera)->frames());
  if (Status s = start_case(fw, board); !s) return stop_case(fw, board, spec.name, s.error(), err);
  Director director(spec, spec.kind == CaseKind::collaborate ? 1 : attempts, scripts, board.simulation().world(),
                    seed * 1000003 + index);
  CaseRig rig{spec, fw, board, **camera, director, *names, world.laser_mount};
  const double limit_s = 60.0 + 40.0 * static_cast<double>(attempts);
  const auto wall_start = std::chrono::steady_clock::now();
  double sim_s = 0;
  if (Status s = run_slices(rig, limit_s, result, sim_s, out); !s) return stop_case(fw, board, spec.name, s.error(), err);
  fw.shutdown();
  board.stop();
  result.sim_s = sim_s;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.attempts = director.attempts();
  collect(result, spec, fw, board, **camera);
  for (std::size_t i = 0; i < fw.scheduler().task_count(); ++i) result.stats.push_back(fw.scheduler().stats(i));
  result.passed = check(result);
  print_outcome(out, result);
  if (!report_dir.empty()) write_case_figure(report_dir, spec, index, result, config, fw, board, err);
  return 0;
}

bool write_report(const std::string& path, std::uint64_t seed, std::size_t attempts, const std::vector<CaseOutcome>& cases) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  json::FileSink sink(f);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .line(2).member("scenario", "cobot")
      .line(2).member_uint64("seed", seed)
      .line(2).member_uint64("attempts_per_case", attempts)
      .line(2).key("cases").begin_array();
  for (const CaseOutcome& c : cases) {
    w.line(4).begin_object()
        .member("name", c.name)
        .member_bool("passed", c.passed)
        .member_uint64("attempts", c.attempts)
        .member_uint32("toggles", c.toggles_on + c.toggles_off)
        .member_uint32("expected_toggles", c.expected_toggles)
        .member_uint32("false_toggles", c.false_toggles);
    w.line(5).key("rejections").begin_object();
    for (std::size_t r = 0; r < c.rejections.size(); ++r)
      w.member_uint32(::sen3bot::cobot::to_string(static_cast<TriggerRejection>(r)), c.rejections[r]);
    w.member_uint32("not_the_operator", c.not_the_operator).end_object();
    w.line(5).key("follow").begin_object()
        .member_uint64("samples", c.follow.samples)
        .key("min_m").fixed_or_null(c.follow.min_m, 3)
        .key("mean_m").fixed_or_null(c.follow.mean_m, 3)
        .key("max_m").fixed_or_null(c.follow.max_m, 3)
        .member_uint32("goals", c.follow_goals)
        .member_uint32("border_holds", c.border_holds)
        .key("outside_area_s").fixed_or_null(c.outside_area_s, 2)
        .end_object();
    w.line(5).member_uint32("wait4col_entries", c.wait4col_entries)
        .key("post_error_m").fixed_or_null(c.post_error_m, 3)
        .member_bool("waiting_at_end", c.waiting_at_end)
        .member_uint64("contacts", c.contacts)
        .member_uint64("moving_contacts", c.moving_contacts)
        .member_uint64("worker_path_points", c.worker_path_points);
    w.line(5).key("operation").begin_object()
        .member("recognised", c.operation)
        .key("probability").fixed_or_null(c.operation_probability, 4)
        .member_uint32("points", c.operation_points)
        .end_object();
    w.line(5).key("qr").begin_object()
        .member_uint64("frames_rendered", c.frames_rendered)
        .member_uint64("frames_searched", c.frames_searched)
        .member_uint64("tags_read", c.tags_read)
        .end_object();
    w.line(5).key("simulated_s").fixed_or_null(c.sim_s, 1).key("wall_s").fixed_or_null(c.wall_s, 2).key("tasks").begin_array();
    for (const tasks::TaskStats& t : c.stats) {
      w.begin_object()
          .member("name", t.name)
          .member_uint64("runs", t.runs)
          .key("cpu_mean_us").fixed_or_null(static_cast<double>(t.cpu_mean_ns) / 1e3, 1)
          .key("cpu_max_us").fixed_or_null(static_cast<double>(t.cpu_max_ns) / 1e3, 1)
          .end_object();
    }
    w.end_array().end_object();
  }
  w.line(2).end_array().line(0).end_object();
  const bool written = static_cast<bool>(w.finish()) && std::fputc('\n', f) != EOF;
  return std::fclose(f) == 0 && written;
}

}  // namespace

void list_cobot_scenario(std::FILE* out) {
  std::fprintf(out, "cobot: the collaborative mode: operators ask a robot waiting in the lab's work area to follow them, "
                    "and fail to in each way it must refuse (--attempts N per case)\n");
  for (const CobotCase& c : kCases) std::fprintf(out, "  %s: %s\n", c.name, c.description);
}

int cobot_scenario(const std::string& config_path, const std::string& report_dir, std::uint64_t seed, bool have_seed,
                   std::size_t attempts, const std::string& only, std::FILE* out, std::FILE* err) {
  Result<SimulatedRobot> loaded = load_simulated_robot(config_path);
  if (!loaded) {
    std::fprintf(err, "sen3bot-sim sim: %s\n", loaded.error().c_str());
    return 2;
  }
  if (!loaded->firmware.navigation.enabled || loaded->firmware.has_fleet) {
    std::fprintf(err, "sen3bot-sim sim: %s: the cobot scenario needs a navigation section and no fleet section\n",
                 config_path.c_str());
    return 2;
  }
  const std::size_t slash = config_path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "" : config_path.substr(0, slash + 1);
  if (!have_seed) seed = loaded->world.seed;
  std::fprintf(out, "scenario cobot (%zu cases, %zu attempt%s each, lockstep simulated time, seed %llu)\n", kCases.size(),
               attempts, attempts == 1 ? "" : "s", static_cast<unsigned long long>(seed));
  std::vector<CaseOutcome> results;
  int rc = 0;
  for (std::size_t i = 0; i < kCases.size(); ++i) {
    if (!only.empty() && only != kCases[i].name) continue;
    std::fprintf(out, "\ncase %zu/%zu %s: %s\n", i + 1, kCases.size(), kCases[i].name, kCases[i].description);
    CaseOutcome& result = results.emplace_back();
    if (run_cobot_case(kCases[i], i, loaded->firmware, loaded->world, folder, attempts, seed, report_dir, result, out, err) != 0)
      return 1;
    if (!result.passed) rc = 3;
  }
  if (results.empty()) {
    std::fprintf(err, "sen3bot-sim sim: the cobot scenario has no case named '%s'\n", only.c_str());
    return 2;
  }
  std::fprintf(out, "\nsummary of cobot:\n");
  for (const CaseOutcome& r : results) {
    std::fprintf(out, "  %-18s %-7s attempts %2zu  toggles %2u/%-2u  false %u  refused %2u\n", r.name.c_str(),
                 r.passed ? "passed" : "FAILED", r.attempts, r.toggles_on + r.toggles_off, r.expected_toggles,
                 r.false_toggles, refusals(r));
  }
  if (!report_dir.empty()) {
    const std::string json = report_dir + "/report.json";
    if (!write_report(json, seed, attempts, results)) {
      std::fprintf(err, "sen3bot-sim sim: cannot write %s\n", json.c_str());
      return 1;
    }
    std::fprintf(out, "report: %s (report.json and one PNG per case)\n", report_dir.c_str());
  }
  return rc;
}

}  // namespace sen3bot::sim
