// `sen3bot-sim train operations` and `sen3bot-sim experiment operations`: the operation
// recognizer trained on simulated workers of four walking styles and tested on workers of a
// fifth, held-out style (docs/cobot/recognition.md).
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.hpp"
#include "operations_report.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/path_file.hpp"
#include "sen3bot/cobot/recognizer.hpp"
#include "sen3bot/sim/cobot/workers.hpp"
#include "sen3bot/nav/map.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

namespace {

using cobot::Evaluation;
using cobot::FeatureEncoding;
using cobot::LabelledPath;

constexpr const char* kDefaultOperations = "config/cobot/operations.yaml";
constexpr const char* kDefaultModel = "config/cobot/operations-model.yaml.gz";

// The shipped model's training (tools/train_operations.sh runs these): 480 walks per operation,
// 120 in each training style, and a quarter as many again for validation.
struct TrainingPlan {
  std::size_t per_class = 480;
  std::uint64_t seed = 1;
  FeatureEncoding encoding = FeatureEncoding::occupancy_order;
  int hidden = 32;
  int epochs = cobot::TrainingOptions{}.epochs;
  cobot::TrainingOptions options() const {
    cobot::TrainingOptions o;
    o.encoding = encoding;
    o.hidden = {hidden};
    o.epochs = epochs;
    return o;
  }
  std::size_t validation_per_class() const { return std::max<std::size_t>(4, per_class / 4); }
};
constexpr std::size_t kMaxPerClass = 100000;
constexpr std::size_t kMaxHidden = 1024;
constexpr std::size_t kMaxEpochs = 10000;

// The targets: whole-path accuracy on held-out workers, and the right operation above 95 %
// for 95 % of them once 60 % of the path is walked.
constexpr double kTargetAccuracy = 0.97;
constexpr double kConfidentProbability = 0.95;
constexpr double kTargetConfident = 0.95;
constexpr std::size_t kTargetStep = 5;  // kPrefixFractions[5] = 0.6

int bad(std::FILE* err, const char* name, const std::string& message) {
  std::fprintf(err, "%s: %s\n", name, message.c_str());
  return 2;
}

// The site: the operations, their map and the workers on it (the simulator keeps a pointer to
// the map, so both live on the heap).
struct Site {
  cobot::OperationsConfig config;
  std::unique_ptr<nav::OccupancyMap> map;
  std::unique_ptr<cobot::WorkerSimulator> workers;
};

Result<Site> load_site(const std::string& operations_path) {
  Site site;
  Result<cobot::OperationsConfig> config = cobot::load_operations(operations_path);
  if (!config) return config.error();
  site.config = std::move(*config);
  Result<nav::OccupancyMap> map = nav::load_map(site.config.map_path);
  if (!map) return map.error();
  site.map = std::make_unique<nav::OccupancyMap>(std::move(*map));
  Result<std::unique_ptr<cobot::WorkerSimulator>> workers = cobot::WorkerSimulator::create(site.config, *site.map);
  if (!workers) return workers.error();
  site.workers = std::move(*workers);
  return site;
}

double mean_points(const std::vector<LabelledPath>& paths) {
  double n = 0;
  for (const LabelledPath& p : paths) n += static_cast<double>(p.points());
  return paths.empty() ? 0.0 : n / static_cast<double>(paths.size());
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Trained {
  std::unique_ptr<cobot::OperationRecognizer> recognizer;
  cobot::TrainingReport report;
  double generate_s = 0;
};

// Generates the training and validation walks of a plan and trains on them, printing progress.
Result<Trained> train(Site& site, const TrainingPlan& plan, std::FILE* out) {
  const auto start = std::chrono::steady_clock::now();
  cobot::DatasetSpec spec;
  spec.styles = cobot::training_styles();
  spec.per_operation = plan.per_class;
  spec.seed = plan.seed;
  spec.purpose = cobot::kTrainingSeeds;
  Result<std::vector<LabelledPath>> training = cobot::generate_paths(*site.workers, spec);
  if (!training) return training.error();
  spec.per_operation = plan.validation_per_class();
  spec.purpose = cobot::kValidationSeeds;
  Result<std::vector<LabelledPath>> validation = cobot::generate_paths(*site.workers, spec);
  if (!validation) return validation.error();
  Trained t;
  t.generate_s = seconds_since(start);
  std::fprintf(out, "  generated %zu training walks (%.0f points on average) and %zu validation walks in %.1f s\n",
               training->size(), mean_points(*training), validation->size(), t.generate_s);
  std::fflush(out);

  cobot::TrainingOptions options = plan.options();
  char note[256];
  std::snprintf(note, sizeof note,
                "seed %llu; %zu walks per operation in the styles direct, relaxed, hesitant, wide; prefixes 10..100 %%; "
                "hidden %d; %d epochs of back-propagation (%.3g, momentum %.3g)",
                static_cast<unsigned long long>(plan.seed), plan.per_class, plan.hidden, options.epochs,
                options.learning_rate, options.momentum);
  options.note = note;
  std::fprintf(out, "  training the %s network: %zu samples (walks x 10 prefixes%s), %zu inputs, %d hidden, %d epochs...\n",
               cobot::to_string(plan.encoding),
               training->size() * cobot::kProgressSteps * (options.augment ? 3 : 1),
               options.augment ? " x 3: as walked, thinned, shifted" : "",
               cobot::feature_count(site.config.grid, plan.encoding), plan.hidden, options.epochs);
  std::fflush(out);
  Result<std::unique_ptr<cobot::OperationRecognizer>> r =
      cobot::train_recognizer(site.config, *training, *validation, options, &t.report);
  if (!r) return r.error();
  t.recognizer = std::move(*r);
  std::fprintf(out,
               "  trained in %.1f s; validation (training styles): accuracy %.3f whole paths, %.3f over all prefixes; "
               "softmax temperature %.4f\n",
               t.report.seconds, t.report.validation_accuracy, t.report.validation_prefix_accuracy, t.report.temperature);
  std::fflush(out);
  return t;
}

bool parse_count(const char* text, std::size_t max, std::size_t& out) {
  std::uint64_t v = 0;
  if (!firmware::parse_u64(text, v) || v == 0 || v > max) return false;
  out = static_cast<std::size_t>(v);
  return true;
}

// The robot's reference routes as the operations file's `references` block.
Status write_references(Site& site, const std::string& path) {
  std::string text =
      "# BEGIN references: written by `sen3bot-sim train operations --references FILE`"
      " (tools/train_operations.sh); everything below is generated.\n"
      "# The route the robot drives to assist each operation: A* through its stations on the map,\n"
      "# kept 0.5 m off obstacles where the aisles allow, resampled every 0.25 m.\n"
      "references:\n";
  char buf[64];
  for (std::size_t o = 0; o < site.config.operations.size(); ++o) {
    Result<std::vector<msg::Point2D>> route = site.workers->reference_route(o);
    if (!route) return route.error();
    const std::string head = "  " + site.config.operations[o].name + ": [";
    text += head;
    for (std::size_t i = 0; i < route->size(); ++i) {
      std::snprintf(buf, sizeof buf, "[%.2f, %.2f]", (*route)[i].x_m, (*route)[i].y_m);
      text += buf;
      if (i + 1 < route->size()) text += (i % 6 == 5) ? ",\n" + std::string(head.size(), ' ') : ", ";
    }
    text += "]\n";
  }
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!(f << text) || !f.flush()) return Error::format(Errc::io, "%s: cannot write", path.c_str());
  return {};
}

// --- train operations ------------------------------------------------------------------------

constexpr const char* kTrainName = "sen3bot-sim train operations";

int train_operations(int argc, char** argv, std::FILE* out, std::FILE* err) {
  TrainingPlan plan;
  std::string model_path, operations_path = kDefaultOperations, references_path;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) return bad(err, kTrainName, std::string(arg) + ": needs a value");
    const char* value = argv[++i];
    auto value_error = [&](const char* expected) {
      return bad(err, kTrainName, std::string(arg) + ": expected " + expected + ", got '" + value + "'");
    };
    std::size_t n = 0;
    if (arg == "--out") {
      model_path = value;
    } else if (arg == "--operations") {
      operations_path = value;
    } else if (arg == "--references") {
      references_path = value;
    } else if (arg == "--per-class") {
      if (!parse_count(value, kMaxPerClass, plan.per_class)) return value_error("a walk count from 1 to 100000");
    } else if (arg == "--seed") {
      if (!firmware::parse_u64(value, plan.seed)) return value_error("a non-negative integer");
    } else if (arg == "--hidden") {
      if (!parse_count(value, kMaxHidden, n) || n < 2) return value_error("a neuron count from 2 to 1024");
      plan.hidden = static_cast<int>(n);
    } else if (arg == "--epochs") {
      if (!parse_count(value, kMaxEpochs, n)) return value_error("an epoch count from 1 to 10000");
      plan.epochs = static_cast<int>(n);
    } else if (arg == "--encoding") {
      if (!cobot::parse_encoding(value, plan.encoding)) return value_error("occupancy or occupancy_order");
    } else {
      return bad(err, kTrainName, "unknown option " + std::string(arg));
    }
  }
  if (model_path.empty() && references_path.empty())
    return bad(err, kTrainName, "--out MODEL is required (or --references FILE alone)");

  Result<Site> site = load_site(operations_path);
  if (!site) return bad(err, kTrainName, site.error().c_str());
  if (!references_path.empty()) {
    if (Status s = write_references(*site, references_path); !s) {
      std::fprintf(err, "%s: %s\n", kTrainName, s.error().c_str());
      return 1;
    }
    std::fprintf(out, "references: %s\n", references_path.c_str());
    if (model_path.empty()) return 0;
  }
  std::fprintf(out, "train operations: %zu operations from %s, %zu walks each (seed %llu)\n",
               site->config.operations.size(), operations_path.c_str(), plan.per_class,
               static_cast<unsigned long long>(plan.seed));
  std::fflush(out);
  Result<Trained> trained = train(*site, plan, out);
  if (!trained) {
    std::fprintf(err, "%s: %s\n", kTrainName, trained.error().c_str());
    return 1;
  }
  if (Status s = trained->recognizer->save(model_path); !s) {
    std::fprintf(err, "%s: %s\n", kTrainName, s.error().c_str());
    return 1;
  }
  struct stat st {};
  const long long bytes = ::stat(model_path.c_str(), &st) == 0 ? static_cast<long long>(st.st_size) : -1;
  std::fprintf(out, "model: %s (%lld bytes)\n", model_path.c_str(), bytes);
  return 0;
}

// --- experiment operations -------------------------------------------------------------------

constexpr const char* kExperimentName = "sen3bot-sim experiment operations";

struct ExperimentOptions {
  std::size_t runs = 0;
  std::uint64_t seed = 1;
  std::string report_dir;
  std::string model_path = kDefaultModel;
  std::string operations_path = kDefaultOperations;
  std::string save_paths;
  std::string style = cobot::held_out_style().name;
  bool baseline = true;
  bool first_task = false;  // record from the first task on (cobot::Observer::records_first_task)
  TrainingPlan baseline_plan{.encoding = FeatureEncoding::occupancy};
};

// The evaluation's members, one a line at `indent` spaces (the progressive rows 2 deeper).
void write_evaluation(json::Writer& w, const Evaluation& e, std::size_t indent) {
  w.line(indent).member_uint64("paths", e.paths).line(indent).key("accuracy").fixed_or_null(e.accuracy, 6);
  w.line(indent).key("confusion").begin_object()
      .member("rows", "true operation")
      .member("columns", "recognised")
      .key("classes").begin_array();
  for (const std::string& name : e.classes) w.string(name);
  w.end_array().key("matrix").begin_array();
  for (const auto& row : e.confusion) {
    w.begin_array();
    for (const std::size_t n : row) w.uint64(n);
    w.end_array();
  }
  w.end_array().end_object();
  w.line(indent).key("progressive").begin_array();
  for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) {
    w.line(indent + 2).begin_object()
        .key("walked").fixed_or_null(cobot::kPrefixFractions[s], 1)
        .key("right_probability").fixed_or_null(e.right_probability[s], 6)
        .key("right_above_0_95").fixed_or_null(e.confident[s], 6)
        .key("accuracy").fixed_or_null(e.step_accuracy[s], 6)
        .end_object();
  }
  w.line(indent).end_array().line(indent).key("classify_us_median").fixed_or_null(e.median_us, 3);
}

void print_table(std::FILE* out, const char* label, const Evaluation& e) {
  std::fprintf(out, "  %-28s", label);
  for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) std::fprintf(out, " %5.0f%%", 100 * cobot::kPrefixFractions[s]);
  std::fprintf(out, "\n  %-28s", "  mean P(right operation)");
  for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) std::fprintf(out, " %6.3f", e.right_probability[s]);
  std::fprintf(out, "\n  %-28s", "  paths with P(right) > 0.95");
  for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) std::fprintf(out, " %6.3f", e.confident[s]);
  std::fprintf(out, "\n  %-28s", "  accuracy");
  for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) std::fprintf(out, " %6.3f", e.step_accuracy[s]);
  std::fprintf(out, "\n");
}

void print_confusion(std::FILE* out, const Evaluation& e) {
  std::fprintf(out, "  %-12s", "true \\ seen");
  for (const std::string& c : e.classes) std::fprintf(out, " %9.9s", c.c_str());
  std::fprintf(out, "\n");
  for (std::size_t r = 0; r < e.classes.size(); ++r) {
    std::fprintf(out, "  %-12.12s", e.classes[r].c_str());
    for (const std::size_t n : e.confusion[r]) std::fprintf(out, " %9zu", n);
    std::fprintf(out, "\n");
  }
}

// The reversal test: each held-out walk of an operation whose stations, reversed, are another
// operation's, played backwards, should be taken for that other operation. A drawn path is the
// same both ways, so a classifier of the drawing alone answers a walk and its reverse alike and
// gets at most half of the walk-and-reverse pairs right.
struct Reversal {
  std::size_t paths = 0;
  std::size_t right = 0;
  [[nodiscard]] double accuracy() const { return paths ? static_cast<double>(right) / static_cast<double>(paths) : 0.0; }
};

Result<Reversal> reversal_test(cobot::OperationRecognizer& recognizer, const cobot::OperationsConfig& config,
                               const std::vector<LabelledPath>& paths) {
  Reversal r;
  std::vector<float> p(recognizer.operations());
  for (const LabelledPath& path : paths) {
    const std::vector<std::size_t>& stations = config.operations[path.operation].stations;
    int reverse = -1;
    for (std::size_t k = 0; k < config.operations.size(); ++k)
      if (std::equal(stations.begin(), stations.end(), config.operations[k].stations.rbegin(),
                     config.operations[k].stations.rend()))
        reverse = static_cast<int>(k);
    if (reverse < 0) continue;
    std::vector<float> backwards;
    for (std::size_t i = path.points(); i-- > 0;) backwards.insert(backwards.end(), {path.xy[2 * i], path.xy[2 * i + 1]});
    if (Status s = recognizer.classify(backwards, path.points(), p); !s) return s.error();
    ++r.paths;
    r.right += static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin()) == reverse;
  }
  return r;
}

int parse_experiment(int argc, char** argv, ExperimentOptions& o, std::FILE* err) {
  bool have_runs = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--no-baseline") {
      o.baseline = false;
      continue;
    }
    if (arg == "--first-task") {
      o.first_task = true;
      continue;
    }
    if (i + 1 >= argc) return bad(err, kExperimentName, std::string(arg) + ": needs a value");
    const char* value = argv[++i];
    auto value_error = [&](const char* expected) {
      return bad(err, kExperimentName, std::string(arg) + ": expected " + expected + ", got '" + value + "'");
    };
    if (arg == "--runs") {
      if (!parse_count(value, kMaxPerClass, o.runs)) return value_error("a walk count per operation from 1 to 100000");
      have_runs = true;
    } else if (arg == "--seed") {
      if (!firmware::parse_u64(value, o.seed)) return value_error("a non-negative integer");
    } else if (arg == "--report") {
      o.report_dir = value;
    } else if (arg == "--model") {
      o.model_path = value;
    } else if (arg == "--operations") {
      o.operations_path = value;
    } else if (arg == "--save-paths") {
      o.save_paths = value;
    } else if (arg == "--style") {
      if (!cobot::find_style(value)) return value_error("a walking style (direct, relaxed, hesitant, wide, rushed)");
      o.style = value;
    } else if (arg == "--baseline-per-class") {
      if (!parse_count(value, kMaxPerClass, o.baseline_plan.per_class)) return value_error("a walk count from 1 to 100000");
    } else {
      return bad(err, kExperimentName, "unknown option " + std::string(arg));
    }
  }
  if (!have_runs) return bad(err, kExperimentName, "--runs N is required");
  return 0;
}

// What the experiment found: per model (the order-encoded one, then the occupancy-only
// baseline unless --no-baseline) its evaluation on the test walks and its reversal test.
struct Findings {
  std::vector<operations::Labelled> results;
  std::vector<Reversal> reversals;
  cobot::TrainingReport baseline_report;
  double baseline_generate_s = 0;
  [[nodiscard]] const Evaluation& ours() const { return results.front().evaluation; }
  [[nodiscard]] bool accuracy_met() const { return ours().accuracy >= kTargetAccuracy; }
  [[nodiscard]] bool progressive_met() const { return ours().confident[kTargetStep] >= kTargetConfident; }
};

// The held-out workers: their own seed stream, so none of them was seen in training.
Result<std::vector<LabelledPath>> test_walks(Site& site, const cobot::WorkerStyle& style, const ExperimentOptions& o,
                                             std::FILE* out) {
  const auto generate_start = std::chrono::steady_clock::now();
  cobot::DatasetSpec spec;
  spec.styles = std::span<const cobot::WorkerStyle>(&style, 1);
  spec.per_operation = o.runs;
  spec.seed = o.seed;
  spec.purpose = cobot::kTestSeeds;
  spec.records_first_task = o.first_task;
  Result<std::vector<LabelledPath>> test = cobot::generate_paths(*site.workers, spec);
  if (!test) return test.error();
  std::fprintf(out, "  generated %zu walks (%.0f points on average) in %.1f s\n", test->size(), mean_points(*test),
               seconds_since(generate_start));
  std::fflush(out);
  return test;
}

// The thesis' input (the drawn path, no order) with the same classifier and training: trained
// here, evaluated and reversed as the shipped model was. 0, or the exit status of a failure.
int run_baseline(Site& site, const ExperimentOptions& o, const std::vector<LabelledPath>& test, Findings& found,
                 std::FILE* out, std::FILE* err) {
  std::fprintf(out, "  source-style comparison: training on the occupancy image alone (%zu walks per operation)\n",
               o.baseline_plan.per_class);
  std::fflush(out);
  Result<Trained> baseline = train(site, o.baseline_plan, out);
  if (!baseline) {
    std::fprintf(err, "%s: %s\n", kExperimentName, baseline.error().c_str());
    return 1;
  }
  found.baseline_report = baseline->report;
  found.baseline_generate_s = baseline->generate_s;
  Result<Evaluation> b = cobot::evaluate(*baseline->recognizer, test, kConfidentProbability);
  if (!b) return bad(err, kExperimentName, b.error().c_str());
  std::fprintf(out, "  occupancy-only model: accuracy %.3f\n", b->accuracy);
  found.results.push_back({"occupancy only (thesis input)", std::move(*b)});
  Result<Reversal> r = reversal_test(*baseline->recognizer, site.config, test);
  if (!r) return bad(err, kExperimentName, r.error().c_str());
  found.reversals.push_back(*r);
  return 0;
}

void print_findings(std::FILE* out, const cobot::WorkerStyle& style, std::size_t walks, const Findings& found) {
  const Evaluation& ours = found.ours();
  std::fprintf(out, "\nprogressive test (%zu %s walks; prefixes of each recorded path):\n", walks, style.name.c_str());
  for (const operations::Labelled& r : found.results) print_table(out, r.label.c_str(), r.evaluation);
  std::fprintf(out, "\nconfusion, whole paths (order-encoded):\n");
  print_confusion(out, ours);
  if (found.results.size() > 1) {
    std::fprintf(out, "confusion, whole paths (occupancy only):\n");
    print_confusion(out, found.results[1].evaluation);
  }

  if (found.reversals.front().paths > 0) {
    std::fprintf(out, "reversal test (%zu walks of operations with a reversed twin, played backwards):",
                 found.reversals.front().paths);
    for (std::size_t k = 0; k < found.reversals.size(); ++k)
      std::fprintf(out, "%s %s %.3f", k ? "," : "", found.results[k].label.c_str(), found.reversals[k].accuracy());
    std::fprintf(out, "\n");
  }

  const bool accuracy_met = found.accuracy_met();
  const bool progressive_met = found.progressive_met();
  std::fprintf(out, "\ntargets: accuracy %.3f %s 0.97 (%s); right operation above 0.95 at 60 %% for %.1f %% of paths %s 95 %% (%s)\n",
               ours.accuracy, accuracy_met ? ">=" : "<", accuracy_met ? "met" : "NOT met",
               100 * ours.confident[kTargetStep], progressive_met ? ">=" : "<", progressive_met ? "met" : "NOT met");
}

// --save-paths: the walks as a paths file for `sen3bot recognize`.
bool save_paths(const std::string& path, const Site& site, const cobot::WorkerStyle& style,
                const std::vector<LabelledPath>& test) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  std::size_t index = 0;
  for (const LabelledPath& p : test) {
    cobot::PathRecord r{style.name + "-" + std::to_string(index++), site.config.operations[p.operation].name, p.xy};
    f << cobot::path_line(r) << '\n';
  }
  return static_cast<bool>(f.flush());
}

bool write_report_json(const std::string& path, const ExperimentOptions& o, const cobot::WorkerStyle& style, bool held_out,
                       const std::vector<LabelledPath>& test, const Findings& found) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return false;
  json::FileSink sink(f);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .line(2).member("experiment", "operations")
      .line(2).member("operations_file", o.operations_path)
      .line(2).member("model", o.model_path)
      .line(2).member("style", style.name)
      .line(2).member_bool("held_out_style", held_out)
      .line(2).member_uint64("runs_per_operation", o.runs)
      .line(2).member_uint64("seed", o.seed)
      .line(2).member_bool("recorded_from_first_task", o.first_task);
  write_evaluation(w, found.ours(), 2);
  w.line(2).key("targets").begin_object()
      .key("accuracy").fixed_or_null(kTargetAccuracy, 2)
      .member_bool("accuracy_met", found.accuracy_met())
      .key("confident_at_60_percent").fixed_or_null(kTargetConfident, 2)
      .member_bool("confident_met", found.progressive_met())
      .end_object();
  if (found.results.size() > 1) {
    w.line(2).key("source_style").begin_object()
        .line(4).member("encoding", "occupancy")
        .line(4).member_uint64("training_walks_per_operation", o.baseline_plan.per_class)
        .line(4).key("training_s").fixed_or_null(found.baseline_report.seconds, 3)
        .line(4).key("generation_s").fixed_or_null(found.baseline_generate_s, 3);
    write_evaluation(w, found.results[1].evaluation, 4);
    w.line(2).end_object();
  }
  w.line(2).key("reversal").begin_object()
      .member_uint64("paths", found.reversals.front().paths)
      .key("order_encoded_accuracy").fixed_or_null(found.reversals.front().accuracy(), 6);
  if (found.reversals.size() > 1) w.key("occupancy_only_accuracy").fixed_or_null(found.reversals[1].accuracy(), 6);
  w.end_object();
  w.line(2).key("timing").begin_object()
      .key("classify_us_median").fixed_or_null(found.ours().median_us, 3)
      .key("points_mean").fixed_or_null(mean_points(test), 1)
      .end_object();
  w.line(0).end_object();
  const bool written = static_cast<bool>(w.finish()) && std::fputc('\n', f) != EOF;
  return std::fclose(f) == 0 && written;
}

// confusion.png, progressive.png and paths.png (the first test walk of each operation).
bool draw_figures(const std::string& report_dir, const std::string& subtitle, const Site& site,
                  const std::vector<LabelledPath>& test, const Findings& found) {
  bool ok = operations::draw_confusion("Operation recognition: whole paths", subtitle, found.results)
                .write_png(report_dir + "/confusion.png");
  ok = operations::draw_progressive("Operation recognition as the path grows", subtitle, found.results, kConfidentProbability)
           .write_png(report_dir + "/progressive.png") && ok;
  std::vector<operations::ExamplePath> examples;
  for (std::size_t op = 0; op < site.config.operations.size(); ++op) {
    for (const LabelledPath& p : test) {
      if (p.operation != op) continue;
      std::string label = site.config.operations[op].name + "\n";
      for (const std::size_t s : site.config.operations[op].stations)
        label += (label.back() == '\n' ? "" : " > ") + site.config.stations[s].name;
      examples.push_back({label, p.xy});
      break;
    }
  }
  ok = operations::draw_example_paths("Recorded paths, one per operation", subtitle, *site.map, site.config, examples)
           .write_png(report_dir + "/paths.png") && ok;
  return ok;
}

}  // namespace

int train_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc < 1 || std::string_view(argv[0]) != "operations")
    return bad(err, "sen3bot-sim train", "what to train? (there is one: operations)");
  return train_operations(argc - 1, argv + 1, out, err);
}

int operations_experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  ExperimentOptions o;
  if (int rc = parse_experiment(argc, argv, o, err); rc != 0) return rc;
  if (!o.report_dir.empty()) {
    if (::mkdir(o.report_dir.c_str(), 0755) != 0 && errno != EEXIST)
      return bad(err, kExperimentName, "--report: cannot create " + o.report_dir + ": " + std::strerror(errno));
  }
  Result<Site> site = load_site(o.operations_path);
  if (!site) return bad(err, kExperimentName, site.error().c_str());
  Result<std::unique_ptr<cobot::OperationRecognizer>> model = cobot::OperationRecognizer::load(o.model_path, site->config);
  if (!model) return bad(err, kExperimentName, model.error().c_str());
  const cobot::WorkerStyle& style = *cobot::find_style(o.style);
  const bool held_out = style.name == cobot::held_out_style().name;

  std::fprintf(out, "experiment operations: %zu operations, %zu %s workers each (seed %llu%s%s), model %s\n",
               site->config.operations.size(), o.runs, style.name.c_str(), static_cast<unsigned long long>(o.seed),
               held_out ? ", a style not used in training" : ", a TRAINING style",
               o.first_task ? ", recorded from their first task" : "", o.model_path.c_str());
  std::fflush(out);
  Result<std::vector<LabelledPath>> test = test_walks(*site, style, o, out);
  if (!test) return bad(err, kExperimentName, test.error().c_str());

  Result<Evaluation> ours = cobot::evaluate(**model, *test, kConfidentProbability);
  if (!ours) return bad(err, kExperimentName, ours.error().c_str());
  std::fprintf(out, "  order-encoded model: accuracy %.3f, classification %.1f us per path (median)\n", ours->accuracy,
               ours->median_us);
  std::fflush(out);
  Findings found;
  found.results.push_back({"order-encoded", *ours});
  Result<Reversal> reversal = reversal_test(**model, site->config, *test);
  if (!reversal) return bad(err, kExperimentName, reversal.error().c_str());
  found.reversals.push_back(*reversal);
  if (o.baseline)
    if (int rc = run_baseline(*site, o, *test, found, out, err); rc != 0) return rc;
  print_findings(out, style, test->size(), found);

  if (!o.save_paths.empty()) {
    if (!save_paths(o.save_paths, *site, style, *test)) return bad(err, kExperimentName, "--save-paths: cannot write " + o.save_paths);
    std::fprintf(out, "paths: %s\n", o.save_paths.c_str());
  }
  if (!o.report_dir.empty()) {
    const std::string json_path = o.report_dir + "/report.json";
    if (!write_report_json(json_path, o, style, held_out, *test, found))
      return bad(err, kExperimentName, "--report: cannot write " + json_path);
    const std::string subtitle = std::to_string(o.runs) + " " + style.name + " workers per operation (" +
                                 (held_out ? "a walking style not used in training" : "a training style") +
                                 (o.first_task ? ", recorded from their first task" : "") + "), seed " +
                                 std::to_string(o.seed);
    if (!draw_figures(o.report_dir, subtitle, *site, *test, found))
      return bad(err, kExperimentName, "--report: cannot write the figures in " + o.report_dir);
    std::fprintf(out, "report: %s (report.json, confusion.png, progressive.png, paths.png)\n", o.report_dir.c_str());
  }
  return 0;
}

}  // namespace sen3bot::sim
