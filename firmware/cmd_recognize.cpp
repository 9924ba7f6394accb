// `sen3bot recognize`: the operation recognizer on recorded paths (docs/cobot/recognition.md),
// the model the robot runs, on a paths file: per path the probability of each operation, and
// with --progressive the right operation's probability at every 10 % of the path, the table
// of the thesis' progressive test.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "commands.hpp"
#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/path_file.hpp"
#include "sen3bot/cobot/recognizer.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kRecognizeUsage =
    "usage: sen3bot recognize --paths FILE [--progressive] [--model M] [--operations O]\n";
constexpr const char* kDefaultOperations = "config/cobot/operations.yaml";
constexpr const char* kDefaultModel = "config/cobot/operations-model.yaml.gz";

std::size_t best_of(const std::vector<float>& p) {
  return static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin());
}

}  // namespace

int recognize_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string paths_path, model_path = kDefaultModel, operations_path = kDefaultOperations;
  bool progressive = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--progressive") {
      progressive = true;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot recognize: %s needs a value\n%s", argv[i], kRecognizeUsage);
      return 2;
    }
    const std::string value = argv[++i];
    if (arg == "--paths") {
      paths_path = value;
    } else if (arg == "--model") {
      model_path = value;
    } else if (arg == "--operations") {
      operations_path = value;
    } else {
      std::fprintf(err, "sen3bot recognize: unknown option '%s'\n%s", argv[i - 1], kRecognizeUsage);
      return 2;
    }
  }
  if (paths_path.empty()) {
    std::fprintf(err, "sen3bot recognize: --paths is required\n%s", kRecognizeUsage);
    return 2;
  }
  Result<cobot::OperationsConfig> config = cobot::load_operations(operations_path);
  if (!config) {
    std::fprintf(err, "sen3bot recognize: %s\n", config.error().c_str());
    return 2;
  }
  Result<std::unique_ptr<cobot::OperationRecognizer>> recognizer = cobot::OperationRecognizer::load(model_path, *config);
  if (!recognizer) {
    std::fprintf(err, "sen3bot recognize: %s\n", recognizer.error().c_str());
    return 2;
  }
  Result<std::vector<cobot::PathRecord>> paths = cobot::load_paths(paths_path);
  if (!paths) {
    std::fprintf(err, "sen3bot recognize: %s\n", paths.error().c_str());
    return 2;
  }
  const std::vector<std::string>& classes = (*recognizer)->info().classes;
  for (std::size_t k = 0; k < paths->size(); ++k) {
    const cobot::PathRecord& p = (*paths)[k];
    if (!p.operation.empty() && config->find_operation(p.operation) < 0) {
      std::fprintf(err, "sen3bot recognize: %s: path %zu (%s): no operation named '%s' in %s\n", paths_path.c_str(),
                   k + 1, p.name.c_str(), p.operation.c_str(), operations_path.c_str());
      return 2;
    }
  }

  std::vector<float> probability(classes.size());
  std::size_t judged = 0, right = 0;
  std::vector<double> right_sum(cobot::kProgressSteps, 0.0);
  std::size_t name_width = 4;
  for (const std::string& c : classes) name_width = std::max(name_width, c.size());
  for (std::size_t k = 0; k < paths->size(); ++k) {
    const cobot::PathRecord& p = (*paths)[k];
    const std::string name = p.name.empty() ? "path " + std::to_string(k + 1) : p.name;
    if (p.points() == 0) {
      std::fprintf(out, "%s: no points\n", name.c_str());
      continue;
    }
    if (Status s = (*recognizer)->classify(p.xy, p.points(), probability); !s) {
      std::fprintf(err, "sen3bot recognize: %s: %s\n", name.c_str(), s.error().c_str());
      return 1;
    }
    const std::size_t best = best_of(probability);
    const int truth = p.operation.empty() ? -1 : config->find_operation(p.operation);
    std::fprintf(out, "%s (%zu points%s%s): %s", name.c_str(), p.points(), truth >= 0 ? ", truth " : "",
                 truth >= 0 ? p.operation.c_str() : "", classes[best].c_str());
    if (truth >= 0) std::fprintf(out, " %s", static_cast<std::size_t>(truth) == best ? "(right)" : "(WRONG)");
    std::fprintf(out, "\n ");
    for (std::size_t c = 0; c < classes.size(); ++c) std::fprintf(out, " %s %.3f", classes[c].c_str(), probability[c]);
    std::fprintf(out, "\n");
    if (truth >= 0) {
      ++judged;
      right += static_cast<std::size_t>(truth) == best;
    }
    if (!progressive) continue;
    // The thesis' table: at each step the most probable operation and its probability, and the
    // right operation's probability when the truth is known.
    std::fprintf(out, "  %-*s", static_cast<int>(name_width), "walked");
    for (const double f : cobot::kPrefixFractions) std::fprintf(out, " %*.0f%%", static_cast<int>(name_width), 100 * f);
    std::vector<std::size_t> bests;
    std::vector<float> best_p, right_p;
    for (std::size_t s = 0; s < cobot::kProgressSteps; ++s) {
      const std::size_t n = cobot::prefix_points(p.points(), cobot::kPrefixFractions[s]);
      if (Status st = (*recognizer)->classify(p.xy, n, probability); !st) {
        std::fprintf(err, "sen3bot recognize: %s: %s\n", name.c_str(), st.error().c_str());
        return 1;
      }
      bests.push_back(best_of(probability));
      best_p.push_back(probability[bests.back()]);
      right_p.push_back(truth >= 0 ? probability[static_cast<std::size_t>(truth)] : 0.0f);
      if (truth >= 0) right_sum[s] += probability[static_cast<std::size_t>(truth)];
    }
    std::fprintf(out, "\n  %-*s", static_cast<int>(name_width), "best");
    for (const std::size_t b : bests) std::fprintf(out, " %*s", static_cast<int>(name_width + 1), classes[b].c_str());
    std::fprintf(out, "\n  %-*s", static_cast<int>(name_width), "P(best)");
    for (const float v : best_p) std::fprintf(out, " %*.3f", static_cast<int>(name_width + 1), v);
    if (truth >= 0) {
      std::fprintf(out, "\n  %-*s", static_cast<int>(name_width), "P(right)");
      for (const float v : right_p) std::fprintf(out, " %*.3f", static_cast<int>(name_width + 1), v);
    }
    std::fprintf(out, "\n");
  }
  if (judged > 0) {
    std::fprintf(out, "%zu of %zu paths recognised (accuracy %.3f)\n", right, judged,
                 static_cast<double>(right) / static_cast<double>(judged));
    if (progressive) {
      std::fprintf(out, "mean P(right) at");
      for (std::size_t s = 0; s < cobot::kProgressSteps; ++s)
        std::fprintf(out, " %.0f%%: %.3f%s", 100 * cobot::kPrefixFractions[s], right_sum[s] / static_cast<double>(judged),
                     s + 1 < cobot::kProgressSteps ? "," : "\n");
    }
  }
  return 0;
}

}  // namespace sen3bot::firmware
