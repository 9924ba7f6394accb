// `sen3bot-sim experiment crowd`: the crowd-navigation benchmark (docs/crowd.md, "The
// benchmark"). N runs per variant, each a whole firmware in lockstep from config/crowd.yaml on a
// scene drawn from the run's seed (crowd/scene.hpp), its people moved by a crowd model. The runs
// go to worker processes (mission_pool.hpp); each run's crowd metrics (crowd/metrics.hpp) come
// from the ground truth, sampled every 50 ms.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.hpp"
#include "config.hpp"
#include "crowd_experiment.hpp"
#include "mission_pool.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/scene.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

using namespace crowd_experiment;

namespace {

constexpr std::uint64_t kMaxPeople = 256;

int bad(std::FILE* err, const std::string& message) {
  std::fprintf(err, "%s: %s\n", kName, message.c_str());
  return 2;
}

int parse_options(int argc, char** argv, Options& o, std::FILE* err) {
  bool have_runs = false, have_people = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    auto value_error = [&](const char* expected) {
      return bad(err, std::string(arg) + ": expected " + expected + ", got '" + argv[i + 1] + "'");
    };
    std::uint64_t u = 0;
    if (arg == "--scene" && has_value) {
      o.scene = argv[++i];
      if (o.scene != "circle" && o.scene != "crossing" && o.scene != "corridor" && o.scene != "square")
        return bad(err, "--scene: no scene named '" + o.scene + "' (circle, crossing, corridor, square; --trajectories FILE for a recording)");
    } else if (arg == "--trajectories" && has_value) {
      o.trajectories = argv[++i];
      if (o.trajectories.empty()) return bad(err, "--trajectories: expected a file");
    } else if (arg == "--people" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > kMaxPeople) return value_error("a person count from 1 to 256");
      o.people = u;
      have_people = true;
      ++i;
    } else if (arg == "--behaviour" && has_value) {
      o.behaviour = crowd::parse_behaviour(argv[i + 1]);
      if (!o.behaviour) return value_error("recorded, social, blind or orca");
      ++i;
    } else if (arg == "--runs" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > pool::kMaxRuns) return value_error("a run count from 1 to 100000");
      o.runs = u;
      have_runs = true;
      ++i;
    } else if (arg == "--seed" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u)) return value_error("a non-negative integer");
      o.seed = u;
      ++i;
    } else if (arg == "--jobs" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > 1024) return value_error("a worker count from 1 to 1024");
      o.jobs = static_cast<long>(u);
      ++i;
    } else if (arg == "--variant" && has_value) {
      const std::string_view name = argv[i + 1];
      Variant v;
      if (name == "default") v = Variant::standard;
      else if (name == "no-people") v = Variant::no_people;
      else if (name == "perfect-perception") v = Variant::perfect_perception;
      else return bad(err, "--variant: no variant named '" + std::string(name) + "' (" + kVariantNames + ")");
      if (std::find(o.variants.begin(), o.variants.end(), v) == o.variants.end()) o.variants.push_back(v);
      ++i;
    } else if (arg == "--realtime") {
      o.realtime = true;
    } else if (arg == "--report" && has_value) {
      o.report_dir = argv[++i];
      if (o.report_dir.empty()) return bad(err, "--report: expected a directory");
    } else if (arg == "--config" && has_value) {
      o.config_path = argv[++i];
    } else {
      return bad(err, "unknown or incomplete option '" + std::string(arg) + "' (sen3bot-sim --help shows the options)");
    }
  }
  if (o.scene.empty() && o.trajectories.empty())
    return bad(err, "--scene NAME (circle, crossing, corridor, square) or --trajectories FILE is required");
  if (!o.scene.empty() && !o.trajectories.empty()) return bad(err, "--scene and --trajectories are alternatives: give one");
  if (!o.trajectories.empty() && have_people)
    return bad(err, "--people is for the simulated scenes: a recording (--trajectories) brings its own people");
  if (!o.trajectories.empty() && o.behaviour && *o.behaviour != crowd::Behaviour::recorded)
    return bad(err, std::string("--behaviour ") + crowd::to_string(*o.behaviour) +
                        ": a recording (--trajectories) is replayed as it was (--behaviour recorded)");
  if (!o.scene.empty() && o.behaviour && *o.behaviour == crowd::Behaviour::recorded)
    return bad(err, "--behaviour recorded needs --trajectories FILE");
  if (!have_runs) return bad(err, "--runs N is required");
  if (o.variants.empty()) o.variants = {Variant::standard, Variant::no_people, Variant::perfect_perception};
  if (o.jobs == 0) o.jobs = std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN));
  return 0;
}

// The scene's map: in the report folder, or in a temporary folder removed at the end.
struct MapFolder {
  std::string dir;
  bool temporary = false;
  std::string yaml;
  ~MapFolder() {
    if (!temporary || dir.empty()) return;
    if (!yaml.empty()) {
      std::remove(yaml.c_str());
      std::remove((yaml.substr(0, yaml.size() - 5) + ".pgm").c_str());
    }
    ::rmdir(dir.c_str());
  }
};

// The configuration and the report folder, checked before any run.
int load_config(Plan& plan, std::FILE* err) {
  const Options& o = plan.options;
  Result<SimulatedRobot> loaded = load_simulated_robot(o.config_path);
  if (!loaded) return bad(err, loaded.error().c_str());
  plan.base = std::move(loaded->firmware);
  plan.base_world = std::move(loaded->world);
  if (!plan.base.navigation.enabled || plan.base.has_fleet)
    return bad(err, o.config_path + ": needs a navigation section (and no fleet section)");
  if (!o.report_dir.empty()) {
    if (::mkdir(o.report_dir.c_str(), 0755) != 0 && errno != EEXIST)
      return bad(err, "--report: cannot create " + o.report_dir + ": " + std::strerror(errno));
    struct stat st {};
    if (::stat(o.report_dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || ::access(o.report_dir.c_str(), W_OK | X_OK) != 0)
      return bad(err, "--report: " + o.report_dir + " is not a writable directory");
  }
  return 0;
}

// The scene's floor (the same for every seed) as the runs' map, in the report folder or a
// temporary one; false when it cannot be written (said on err).
bool write_map(const crowd::Scene& first, Plan& plan, MapFolder& maps, std::FILE* err) {
  const Options& o = plan.options;
  if (o.report_dir.empty()) {
    char dir[] = "/tmp/sen3bot-crowd-XXXXXX";
    if (::mkdtemp(dir) == nullptr) {
      std::fprintf(err, "%s: cannot create a temporary folder: %s\n", kName, std::strerror(errno));
      return false;
    }
    maps.dir = dir;
    maps.temporary = true;
  } else {
    maps.dir = o.report_dir;
  }
  Result<std::string> map = crowd::write_scene_map(first, maps.dir);
  if (!map) {
    std::fprintf(err, "%s: the scene's map: %s\n", kName, map.error().c_str());
    return false;
  }
  maps.yaml = *map;
  plan.map_path = *map;
  return true;
}

void print_start(std::FILE* out, const Options& o, const std::string& scene_text) {
  std::string variant_list;
  for (const Variant v : o.variants) variant_list += std::string(variant_list.empty() ? "" : ", ") + name_of(v);
  std::fprintf(out, "experiment crowd: %s, %llu run%s per variant (seeds %llu..%llu), variants %s, %ld worker%s, %s\n",
               scene_text.c_str(), static_cast<unsigned long long>(o.runs), o.runs == 1 ? "" : "s",
               static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1),
               variant_list.c_str(), o.jobs, o.jobs == 1 ? "" : "s", o.realtime ? "real time over ptys" : "lockstep");
  std::fflush(out);
}

std::string scene_name(const Options& o) { return o.trajectories.empty() ? o.scene : "recorded"; }

// The plan's jobs on the worker processes, a progress line every so many runs; false when a run
// could not run or the pool failed (said on err).
bool run_all(const Plan& plan, std::chrono::steady_clock::time_point wall_start, std::vector<CrowdRun>& results,
             std::FILE* out, std::FILE* err) {
  const Options& o = plan.options;
  const std::size_t total = plan.jobs.size();
  const std::size_t every = std::max<std::size_t>(1, std::min<std::size_t>(10, total / 20));
  std::size_t done = 0;
  struct Tally {
    std::size_t runs = 0, successes = 0, collisions = 0, timeouts = 0;
  };
  std::vector<Tally> tallies(o.variants.size());
  const std::string name = scene_name(o);
  pool::Callbacks<CrowdRun> callbacks;
  callbacks.run = [&plan](std::size_t j) { return run_job(plan, j); };
  callbacks.accept = [&](std::size_t, const CrowdRun& r) -> std::string {
    if (!r.ran)
      return "seed " + std::to_string(r.seed) + " (" + name_of(r.variant) + "): the run could not run: " + r.error;
    ++done;
    for (std::size_t v = 0; v < o.variants.size(); ++v)
      if (o.variants[v] == r.variant) {
        Tally& t = tallies[v];
        ++t.runs;
        t.successes += r.metrics.success ? 1 : 0;
        t.collisions += r.metrics.contacts_by_robot > 0 ? 1 : 0;
        t.timeouts += r.metrics.timeout ? 1 : 0;
      }
    if (done % every == 0 || done == total) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      std::fprintf(out, "crowd %s: %zu/%zu runs (%.0f s)", name.c_str(), done, total, elapsed);
      for (std::size_t v = 0; v < o.variants.size(); ++v)
        std::fprintf(out, "; %s %zu done, %zu success%s, %zu collision%s, %zu timeout%s so far", name_of(o.variants[v]),
                     tallies[v].runs, tallies[v].successes, tallies[v].successes == 1 ? "" : "es", tallies[v].collisions,
                     tallies[v].collisions == 1 ? "" : "s", tallies[v].timeouts, tallies[v].timeouts == 1 ? "" : "s");
      std::fprintf(out, "\n");
      std::fflush(out);
    }
    return {};
  };
  callbacks.describe = [&plan](std::size_t j) {
    return "seed " + std::to_string(plan.jobs[j].seed) + " (" + name_of(plan.jobs[j].variant) + ")";
  };
  return pool::run_pool(kName, total, static_cast<std::size_t>(o.jobs), callbacks, results, out, err);
}

// report.json, runs.csv, the box plot and the sample run's figure; false when one cannot be
// written (said on err).
bool write_report(const Plan& plan, std::size_t people, const std::string& scene_text, const std::vector<CrowdRun>& results,
                  const std::vector<VariantResults>& by_variant, std::FILE* out, std::FILE* err) {
  const Options& o = plan.options;
  const std::string json = o.report_dir + "/report.json";
  if (!write_report_json(json, o, people, by_variant)) {
    std::fprintf(err, "%s: cannot write %s\n", kName, json.c_str());
    return false;
  }
  const std::string csv = o.report_dir + "/runs.csv";
  if (!write_runs_csv(csv, results)) {
    std::fprintf(err, "%s: cannot write %s\n", kName, csv.c_str());
    return false;
  }
  const std::string box_png = o.report_dir + "/time_to_goal.png";
  if (!write_time_box_plot(box_png, o, scene_text, by_variant)) {
    std::fprintf(err, "%s: cannot write %s\n", kName, box_png.c_str());
    return false;
  }
  // The sample: the first variant's run that came closest to a person (the first such seed).
  const VariantResults& sampled = by_variant.front();
  const CrowdRun* sample = nullptr;
  for (const CrowdRun* r : sampled.runs)
    if (sample == nullptr || r->metrics.min_distance_m < sample->metrics.min_distance_m) sample = r;
  const std::string sample_png = o.report_dir + "/sample_run.png";
  if (sample != nullptr) {
    std::fprintf(out, "the sample run (seed %llu, %s) again, for its figure\n", static_cast<unsigned long long>(sample->seed),
                 name_of(sample->variant));
    std::fflush(out);
    if (!write_sample_figure(plan, sample->job, sample_png, scene_text, err)) {
      std::fprintf(err, "%s: cannot write %s\n", kName, sample_png.c_str());
      return false;
    }
  }
  std::fprintf(out, "report: %s (report.json, runs.csv, time_to_goal.png, sample_run.png, the scene's map)\n",
               o.report_dir.c_str());
  return true;
}

}  // namespace

int crowd_experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  Plan plan;
  Options& o = plan.options;
  if (int rc = parse_options(argc, argv, o, err); rc != 0) return rc;

  if (!o.trajectories.empty()) {
    Result<crowd::Recording> recording = crowd::load_recording(o.trajectories);
    if (!recording) return bad(err, recording.error().c_str());
    plan.recording = std::make_shared<const crowd::Recording>(std::move(*recording));
  }
  // The first run's scene: its options checked before any worker starts, and its floor (the
  // same for every seed) written as the map.
  Result<crowd::Scene> first = make_run_scene(plan, o.seed);
  if (!first) return bad(err, first.error().c_str());
  std::size_t people = first->crowd.behaviour == crowd::Behaviour::recorded && first->crowd.recording
                           ? first->crowd.recording->tracks.size()
                           : first->crowd.people.size();
  if (int rc = load_config(plan, err); rc != 0) return rc;
  MapFolder maps;
  if (!write_map(*first, plan, maps, err)) return 1;

  for (std::uint64_t i = 0; i < o.runs; ++i)
    for (const Variant v : o.variants) plan.jobs.push_back({o.seed + i, v});
  const std::string scene_text = describe_scene(o, people, first->crowd.behaviour);
  print_start(out, o, scene_text);

  const auto wall_start = std::chrono::steady_clock::now();
  std::vector<CrowdRun> results;
  if (!run_all(plan, wall_start, results, out, err)) return 1;
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  std::vector<VariantResults> by_variant;
  double run_wall_s = 0;
  for (const CrowdRun& r : results) run_wall_s += r.wall_s;
  for (const Variant v : o.variants) {
    std::vector<const CrowdRun*> runs;
    for (const CrowdRun& r : results)
      if (r.variant == v) runs.push_back(&r);
    by_variant.push_back(summarize(v, std::move(runs)));
  }
  char head[96];
  std::snprintf(head, sizeof head, "%s, N = %llu", scene_name(o).c_str(), static_cast<unsigned long long>(o.runs));
  print_table(out, by_variant, head);
  std::fprintf(out, "%zu runs in %.1f s wall, %.2f s of one core per run\n", results.size(), wall_s,
               results.empty() ? 0.0 : run_wall_s / static_cast<double>(results.size()));

  if (!o.report_dir.empty() && !write_report(plan, people, scene_text, results, by_variant, out, err)) return 1;
  std::fflush(out);
  return 0;
}

}  // namespace sen3bot::sim
