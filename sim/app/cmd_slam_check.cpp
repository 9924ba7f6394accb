// `sen3bot-sim slam-check`: a mapping trajectory's self-consistency between scans far apart in
// time (slam_check.hpp), for the trajectories of `sen3bot map --poses` and the raw odometry, on
// each trajectory's own pairs and on one common set; the maps drawn at each trajectory's poses.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"
#include "sim_commands.hpp"
#include "slam_check.hpp"

namespace sen3bot::sim {

namespace {

using namespace slam_check;

constexpr const char* kSlamCheckName = "sen3bot-sim slam-check";
constexpr const char* kSlamCheckUsage =
    "usage: sen3bot-sim slam-check --carmen LOG [--poses NAME=FILE ...] [--odometry] [--figure DIR]\n"
    "                              [--min-gap N] [--max-distance M]\n";
constexpr std::size_t kWorstShown = 5;

struct SlamCheckOptions {
  std::string carmen_path;
  struct Named {
    std::string name;
    std::string path;
  };
  std::vector<Named> poses;
  bool odometry = false;
  std::string figure_dir;
  PairOptions pairs;
};

struct Trajectory {
  std::string name;
  std::string source;  // the poses file, or "odometry"
  std::vector<nav::Pose2D> poses;
  std::vector<ScanPair> own;
  std::map<ScanPair, PairCheck> checks;  // own and common pairs, each matched once
  std::string figure_path;
};

int slam_check_error(std::FILE* err, const std::string& message) {
  std::fprintf(err, "%s: %s\n", kSlamCheckName, message.c_str());
  return 2;
}

int parse_slam_check_options(int argc, char** argv, SlamCheckOptions& o, std::FILE* err) {
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    std::uint64_t u = 0;
    double d = 0.0;
    if (arg == "--carmen" && has_value) {
      o.carmen_path = argv[++i];
    } else if (arg == "--poses" && has_value) {
      const std::string value = argv[++i];
      const std::size_t eq = value.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == value.size())
        return slam_check_error(err, "--poses: expected NAME=FILE, got '" + value + "'");
      o.poses.push_back({value.substr(0, eq), value.substr(eq + 1)});
    } else if (arg == "--odometry") {
      o.odometry = true;
    } else if (arg == "--figure" && has_value) {
      o.figure_dir = argv[++i];
      if (o.figure_dir.empty()) return slam_check_error(err, "--figure: expected a directory");
    } else if (arg == "--min-gap" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > 1000000)
        return slam_check_error(err, std::string("--min-gap: expected scans from 1 to 1000000, got '") + argv[i + 1] + "'");
      o.pairs.min_gap = static_cast<std::size_t>(u);
      ++i;
    } else if (arg == "--max-distance" && has_value) {
      if (!firmware::parse_double(argv[i + 1], d) || !(d > 0.0) || d > 100.0)
        return slam_check_error(err, std::string("--max-distance: expected metres in (0, 100], got '") + argv[i + 1] + "'");
      o.pairs.max_distance_m = d;
      ++i;
    } else {
      std::fprintf(err, "%s: unknown or incomplete option '%s'\n%s", kSlamCheckName, argv[i], kSlamCheckUsage);
      return 2;
    }
  }
  if (o.carmen_path.empty()) {
    std::fprintf(err, "%s: --carmen LOG is required\n%s", kSlamCheckName, kSlamCheckUsage);
    return 2;
  }
  if (o.poses.empty() && !o.odometry) {
    std::fprintf(err, "%s: nothing to check: give --poses NAME=FILE or --odometry\n%s", kSlamCheckName, kSlamCheckUsage);
    return 2;
  }
  for (std::size_t a = 0; a < o.poses.size(); ++a) {
    if (o.odometry && o.poses[a].name == "odometry")
      return slam_check_error(err, "--poses: the name 'odometry' is --odometry's");
    for (std::size_t b = 0; b < a; ++b)
      if (o.poses[a].name == o.poses[b].name)
        return slam_check_error(err, "--poses: two trajectories named '" + o.poses[a].name + "'");
  }
  return 0;
}

// The figure's file name: the trajectory's name with anything but letters, digits, '-', '_'
// and '.' as '_'.
std::string figure_file(const std::string& dir, const std::string& name) {
  std::string safe = name;
  for (char& c : safe) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.';
    if (!ok) c = '_';
  }
  if (safe.empty() || safe[0] == '.') safe = "_" + safe;
  return dir + "/" + safe + ".png";
}

std::string base_name(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::vector<PairCheck> checks_of(const Trajectory& t, const std::vector<ScanPair>& pairs) {
  std::vector<PairCheck> out;
  out.reserve(pairs.size());
  for (const ScanPair& p : pairs) out.push_back(t.checks.at(p));
  return out;
}

void write_stats(json::Writer& w, std::string_view name, const Stats& s, int decimals) {
  w.key(name).begin_object();
  w.key("mean").fixed_or_null(s.mean, decimals);
  w.key("median").fixed_or_null(s.median, decimals);
  w.key("p95").fixed_or_null(s.p95, decimals);
  w.end_object();
}

void write_summary(json::Writer& w, std::string_view name, std::span<const PairCheck> checks, bool worst) {
  const Summary s = summarise(checks);
  w.key(name).begin_object();
  w.member_uint64("pairs", s.pairs).member_uint64("matched", s.matched).member_uint64("not_matched", s.pairs - s.matched);
  w.member_uint64("matched_at_window_edge", s.matched_at_window_edge);
  w.key("score_median").fixed_or_null(s.score_median, 3);
  write_stats(w, "translation_m", s.translation_m, 4);
  write_stats(w, "rotation_deg", s.rotation_deg, 3);
  if (worst) {
    // The matched pairs that disagree most, for a look at the scans.
    std::vector<PairCheck> sorted;
    for (const PairCheck& c : checks)
      if (c.matched_ok) sorted.push_back(c);
    std::sort(sorted.begin(), sorted.end(), [](const PairCheck& a, const PairCheck& b) {
      return a.translation_m != b.translation_m ? a.translation_m > b.translation_m : a.pair < b.pair;
    });
    if (sorted.size() > kWorstShown) sorted.resize(kWorstShown);
    w.key("worst").begin_array();
    for (const PairCheck& c : sorted)
      w.begin_object()
          .member_uint64("i", c.pair.i)
          .member_uint64("j", c.pair.j)
          .member_fixed("translation_m", c.translation_m, 4)
          .member_fixed("rotation_deg", c.rotation_deg, 3)
          .member_fixed("score", c.score, 3)
          .member_bool("at_window_edge", c.at_window_edge)
          .end_object();
    w.end_array();
  }
  w.end_object();
}

std::string summary_line(const Summary& s) {
  char line[256];
  if (s.matched == 0)
    std::snprintf(line, sizeof line, "own pairs: %zu, none matched", s.pairs);
  else
    std::snprintf(line, sizeof line,
                  "own pairs: %zu, %zu matched (%zu at the window's edge); disagreement median %.3f m %.2f deg, "
                  "95th percentile %.3f m %.2f deg",
                  s.pairs, s.matched, s.matched_at_window_edge, s.translation_m.median, s.rotation_deg.median,
                  s.translation_m.p95, s.rotation_deg.p95);
  return line;
}

}  // namespace

int slam_check_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  SlamCheckOptions o;
  if (int rc = parse_slam_check_options(argc, argv, o, err); rc != 0) return rc;

  Result<std::vector<Scan>> scans = read_log(o.carmen_path);
  if (!scans) return slam_check_error(err, scans.error().c_str());
  if (scans->empty()) return slam_check_error(err, o.carmen_path + " holds no laser scan");

  std::vector<Trajectory> trajectories;
  for (const SlamCheckOptions::Named& named : o.poses) {
    Result<std::vector<nav::Pose2D>> poses = read_poses(named.path);
    if (!poses) return slam_check_error(err, std::string("--poses ") + named.name + ": " + poses.error().c_str());
    if (poses->size() != scans->size())
      return slam_check_error(err, "--poses " + named.name + ": " + named.path + " holds " + std::to_string(poses->size()) +
                                       " poses, " + o.carmen_path + " holds " + std::to_string(scans->size()) + " scans");
    trajectories.push_back({named.name, named.path, std::move(*poses), {}, {}, {}});
  }
  if (o.odometry) trajectories.push_back({"odometry", "odometry", odometry_poses(*scans), {}, {}, {}});

  if (!o.figure_dir.empty()) {
    if (::mkdir(o.figure_dir.c_str(), 0755) != 0 && errno != EEXIST)
      return slam_check_error(err, "--figure: cannot create " + o.figure_dir + ": " + std::strerror(errno));
    struct stat st {};
    if (::stat(o.figure_dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || ::access(o.figure_dir.c_str(), W_OK | X_OK) != 0)
      return slam_check_error(err, "--figure: " + o.figure_dir + " is not a writable directory");
  }

  // The pairs: each trajectory's own, and the common set from the first.
  const std::vector<ScanPair> common = choose_pairs(trajectories.front().poses, o.pairs);
  std::size_t total = 0;
  for (Trajectory& t : trajectories) {
    t.own = choose_pairs(t.poses, o.pairs);
    for (const ScanPair& p : t.own) t.checks.emplace(p, PairCheck{});
    for (const ScanPair& p : common) t.checks.emplace(p, PairCheck{});
    total += t.checks.size();
  }

  PairChecker checker;
  if (!checker.ready()) {
    std::fprintf(err, "%s: cannot set up the pair grid and matcher\n", kSlamCheckName);
    return 1;
  }
  std::size_t done = 0, shown = 0;
  for (Trajectory& t : trajectories)
    for (auto& [pair, check] : t.checks) {
      check = check_pair(checker, *scans, t.poses, pair);
      ++done;
      if (done * 20 / total > shown) {
        shown = done * 20 / total;
        std::fprintf(err, "\r%s: %zu of %zu pair matches (%s)   ", kSlamCheckName, done, total, t.name.c_str());
        std::fflush(err);
      }
    }
  if (total > 0) std::fputc('\n', err);

  if (!o.figure_dir.empty()) {
    const std::string log_name = base_name(o.carmen_path);
    for (Trajectory& t : trajectories) {
      std::fprintf(err, "%s: drawing the map of %zu scans at the poses of %s\n", kSlamCheckName, scans->size(), t.name.c_str());
      std::fflush(err);
      Result<MapGrid> map = render_map(*scans, t.poses);
      if (!map) {
        std::fprintf(err, "%s: %s: %s\n", kSlamCheckName, t.name.c_str(), map.error().c_str());
        return 1;
      }
      const std::vector<PairCheck> own = checks_of(t, t.own);
      MapFigure f;
      f.title = log_name + ": trajectory " + t.name + " (" + std::to_string(scans->size()) + " scans)";
      f.subtitle = summary_line(summarise(own));
      if (map->resolution_m > kResolutionM + 1e-9) {
        char note[64];
        std::snprintf(note, sizeof note, "; map cells %.2f m", map->resolution_m);
        f.subtitle += note;
      }
      f.map = &*map;
      f.trajectory = t.poses;
      t.figure_path = figure_file(o.figure_dir, t.name);
      if (!draw_map_figure(f).write_png(t.figure_path)) {
        std::fprintf(err, "%s: cannot write %s\n", kSlamCheckName, t.figure_path.c_str());
        return 1;
      }
    }
  }

  json::FileSink sink(out);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object().member("log", o.carmen_path).member_uint64("scans", scans->size());
  w.key("pairs").begin_object()
      .member_uint64("min_gap", o.pairs.min_gap)
      .member_fixed("max_distance_m", o.pairs.max_distance_m, 3)
      .member_fixed("max_angle_deg", o.pairs.max_angle_rad * 180.0 / std::numbers::pi, 1)
      .member_uint64("one_per_scans", o.pairs.stride)
      .member_fixed("window_m", kMatchWindowM, 2)
      .member_fixed("window_deg", kMatchWindowRad * 180.0 / std::numbers::pi, 1)
      .member_fixed("min_score", kMinScore, 2)
      .member_fixed("score_ceiling", score_ceiling(), 3)
      .end_object();
  w.key("common_pairs").begin_object()
      .member("chosen_by", trajectories.front().name)
      .member_uint64("pairs", common.size())
      .end_object();
  w.key("trajectories").begin_array();
  for (const Trajectory& t : trajectories) {
    w.line(2).begin_object().member("name", t.name).member("source", t.source);
    const std::vector<PairCheck> own = checks_of(t, t.own);
    const std::vector<PairCheck> shared = checks_of(t, common);
    write_summary(w, "own", own, true);
    write_summary(w, "common", shared, false);
    if (!t.figure_path.empty()) w.member("figure", t.figure_path);
    w.end_object();
  }
  w.end_array().end_object();
  std::fputc('\n', out);
  if (Result<std::string_view> done_json = w.finish(); !done_json) {
    std::fprintf(err, "%s: %s\n", kSlamCheckName, done_json.error().c_str());
    return 1;
  }
  return 0;
}

}  // namespace sen3bot::sim
