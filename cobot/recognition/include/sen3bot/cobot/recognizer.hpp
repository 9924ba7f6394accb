#pragma once
// Which operation a worker is doing, from the path recorded so far (docs/cobot/recognition.md).
//
// The classifier is OpenCV's multilayer perceptron (cv::ml::ANN_MLP) on the path's features
// (operations.hpp): trained here, in C++, with the same library the robot runs, so the robot
// runs exactly what was trained and training needs nothing but this repository and a seed.
// Its outputs become probabilities through a softmax whose temperature was fitted on held-back
// paths (the one that gives them the least negative log-likelihood).
//
// The model file is OpenCV's FileStorage (YAML, gzip-compressed when the name ends in .gz): the
// network under `opencv_ml_ann_mlp`, and under `sen3bot_operations` the encoding, the grid, the
// class names in order and the temperature. Loading checks them against the operations file.
//
// Not for the real-time thread: classify() runs OpenCV, which may allocate; the robot runs it
// on a worker thread (its input and output matrices are kept between calls).
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::cobot {

struct ModelInfo {
  FeatureEncoding encoding = FeatureEncoding::occupancy_order;
  GridSpec grid;
  std::vector<std::string> classes;  // the operations, in the operations file's order
  std::vector<int> layers;           // neurons per layer, input first
  double temperature = 1.0;          // softmax(outputs / temperature)
  std::string training;              // how it was trained (seed, sizes), for the record
};

class OperationRecognizer {
 public:
  // Reads a model and checks it against the operations: the same operations in the same order
  // and the same grid. Errors name the file and what does not match.
  static Result<std::unique_ptr<OperationRecognizer>> load(const std::string& model_path,
                                                           const OperationsConfig& config);
  ~OperationRecognizer();
  OperationRecognizer(const OperationRecognizer&) = delete;
  OperationRecognizer& operator=(const OperationRecognizer&) = delete;

  // The probability of each operation given the first `points` points of xy (x0, y0, x1, ...);
  // probability must hold operations() values and sums to 1. An empty path is refused.
  Status classify(std::span<const float> xy, std::size_t points, std::span<float> probability);
  // The same from features already computed (feature_count() values).
  Status classify_features(std::span<const float> features, std::span<float> probability);

  Status save(const std::string& path) const;

  [[nodiscard]] const ModelInfo& info() const noexcept;
  [[nodiscard]] std::size_t operations() const noexcept { return info().classes.size(); }
  [[nodiscard]] std::size_t feature_count() const noexcept;

 private:
  friend struct RecognizerAccess;
  struct Impl;
  explicit OperationRecognizer(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// --- Training --------------------------------------------------------------------------------

// The fractions of each path the network learns from, and the progressive test's steps.
inline constexpr std::size_t kProgressSteps = 10;
inline constexpr std::array<double, kProgressSteps> kPrefixFractions{0.1, 0.2, 0.3, 0.4, 0.5,
                                                                     0.6, 0.7, 0.8, 0.9, 1.0};
// The points a prefix of `fraction` keeps: at least one, all of them at 1.
[[nodiscard]] std::size_t prefix_points(std::size_t points, double fraction) noexcept;

struct TrainingOptions {
  FeatureEncoding encoding = FeatureEncoding::occupancy_order;
  std::vector<int> hidden{32};   // hidden layer sizes
  int epochs = 20;               // passes over the samples (back-propagation, shuffled)
  double learning_rate = 0.02;   // ANN_MLP's back-propagation weight scale
  double momentum = 0.1;         // and its moment scale
  bool augment = true;           // also learn from each walk thinned and shifted (recognizer.cpp)
  std::string note;              // stored in the model as ModelInfo::training
};

struct TrainingReport {
  std::size_t samples = 0;             // training rows (walks x copies x prefixes)
  std::size_t validation_samples = 0;
  double seconds = 0;                  // the network's training alone
  double temperature = 1;
  double validation_accuracy = 0;      // whole validation paths
  double validation_prefix_accuracy = 0;  // every prefix of them
  double validation_nll = 0;           // mean negative log-likelihood at that temperature
};

// Trains on every prefix (kPrefixFractions) of the training paths and fits the temperature on
// every prefix of the validation paths. OpenCV runs single-threaded here: its multi-threaded
// back-propagation would sum in a different order from run to run.
Result<std::unique_ptr<OperationRecognizer>> train_recognizer(const OperationsConfig& config,
                                                              std::span<const LabelledPath> training,
                                                              std::span<const LabelledPath> validation,
                                                              const TrainingOptions& options,
                                                              TrainingReport* report = nullptr);

// --- Evaluation ------------------------------------------------------------------------------

struct Evaluation {
  std::vector<std::string> classes;
  std::size_t paths = 0;
  double accuracy = 0;                               // whole paths, most probable operation
  std::vector<std::vector<std::size_t>> confusion;  // [truth][predicted], whole paths
  // Per progress step (kPrefixFractions): the mean probability of the right operation, the
  // fraction of paths where it is above the confidence bar, and the accuracy.
  std::array<double, kProgressSteps> right_probability{};
  std::array<double, kProgressSteps> confident{};
  std::array<double, kProgressSteps> step_accuracy{};
  std::vector<double> classify_us;  // per whole path: features, network and softmax
  double median_us = 0;
};

Result<Evaluation> evaluate(OperationRecognizer& recognizer, std::span<const LabelledPath> paths,
                            double confident_probability = 0.95);

}  // namespace sen3bot::cobot
