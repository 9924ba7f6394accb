#pragma once
// `sen3bot-sim experiment crowd` (cmd_crowd.cpp) in its parts: the plan of runs, one run and the
// sample run's figure (crowd_run.cpp), and the results per variant with the report's table,
// JSON and CSV (crowd_report.cpp).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "config.hpp"
#include "sen3bot/crowd/metrics.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/scene.hpp"
#include "sen3bot/sim/sim_config.hpp"

namespace sen3bot::sim::crowd_experiment {

inline constexpr const char* kName = "sen3bot-sim experiment crowd";

enum class Variant : std::uint8_t { standard, no_people, perfect_perception };
inline const char* name_of(Variant v) {
  return v == Variant::standard ? "default" : v == Variant::no_people ? "no-people" : "perfect-perception";
}
inline constexpr const char* kVariantNames = "default, no-people, perfect-perception";

// One run as a worker reports it: fixed size, no pointers.
struct CrowdRun {
  std::uint64_t seed = 0;
  std::uint32_t job = 0;
  Variant variant = Variant::standard;
  bool ran = false;  // false: the run could not run; `error` says why
  crowd::RunMetrics metrics;
  double sim_s = 0;
  double wall_s = 0;
  char error[256] = {};
};
static_assert(std::is_trivially_copyable_v<CrowdRun>);

struct Options {
  std::string scene;         // circle, crossing, corridor, square
  std::string trajectories;  // or a recording
  std::uint64_t people = 0;  // 0: the scene's default
  std::optional<crowd::Behaviour> behaviour;
  std::uint64_t runs = 0;
  std::uint64_t seed = 1;
  long jobs = 0;  // 0: the online CPUs
  bool realtime = false;  // each mission in real time over ptys
  std::vector<Variant> variants;
  std::string report_dir;
  std::string config_path = "config/crowd.yaml";
};

struct Job {
  std::uint64_t seed = 0;
  Variant variant = Variant::standard;
};

struct Plan {
  Options options;
  firmware::FirmwareConfig base;
  SimulationConfig base_world;
  std::shared_ptr<const crowd::Recording> recording;
  std::string map_path;  // the scene's floor, written once
  std::vector<Job> jobs;
};

// The run's scene: the plan's recording, or its simulated scene drawn from the seed.
Result<crowd::Scene> make_run_scene(const Plan& plan, std::uint64_t seed);
// The plan's job `index`, run quietly (a worker process's part).
CrowdRun run_job(const Plan& plan, std::size_t index);
// The sample run (the job run again with a trace) as a figure at `path`: the people's tracks
// coloured by time, the robot's path and footprint, the contacts and the closest approach.
bool write_sample_figure(const Plan& plan, std::size_t job_index, const std::string& path, const std::string& scene_text,
                         std::FILE* err);

// A variant's runs and what they add up to.
struct VariantResults {
  Variant variant;
  std::vector<const CrowdRun*> runs;
  std::vector<crowd::RunMetrics> metrics;
  crowd::Aggregate aggregate;
  crowd::Rate any_contact;
  crowd::Quartiles time_ratio;  // successful runs
  crowd::Quartiles path_ratio;  // successful runs
  std::vector<double> success_times;
  double mean_cage_entries = 0;
  double mean_jerk = 0;  // mean of the runs' mean jerks
  double max_jerk = 0;   // the largest of any run
};

// A variant's runs summed up.
VariantResults summarize(Variant v, std::vector<const CrowdRun*> runs);
// "crossing scene, 4 social people", or the recording replayed.
std::string describe_scene(const Options& o, std::size_t people, crowd::Behaviour behaviour);
// The results table, a column per variant.
void print_table(std::FILE* out, const std::vector<VariantResults>& variants, const std::string& head);
bool write_report_json(const std::string& path, const Options& o, std::size_t people, const std::vector<VariantResults>& variants);
bool write_runs_csv(const std::string& path, const std::vector<CrowdRun>& runs);
// The successful runs' times to goal, a box per variant.
bool write_time_box_plot(const std::string& path, const Options& o, const std::string& scene_text,
                         const std::vector<VariantResults>& variants);

}  // namespace sen3bot::sim::crowd_experiment
