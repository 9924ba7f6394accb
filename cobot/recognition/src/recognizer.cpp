// The recognizer over cv::ml::ANN_MLP (recognizer.hpp). OpenCV reports errors by throwing
// cv::Exception; every entry point here catches it and returns an Error.
#include "sen3bot/cobot/recognizer.hpp"

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <cmath>
#include <limits>
#include <numeric>

namespace sen3bot::cobot {

namespace {

constexpr const char* kNetworkNode = "opencv_ml_ann_mlp";
constexpr const char* kInfoNode = "sen3bot_operations";
constexpr int kFormat = 1;
// The temperature search's bracket (log-spaced golden section): a useful temperature is well
// inside it.
constexpr double kMinTemperature = 0.005;
constexpr double kMaxTemperature = 20.0;
constexpr int kTemperatureIterations = 60;
constexpr double kMinProbability = 1e-12;  // the log-likelihood's floor
constexpr double kOutputFloor = 1e-3;      // an output this low or lower: "practically never"

// The probabilities from the network's outputs. Trained on (mostly) one-hot targets by least squares,
// each output estimates the probability of its operation; its logarithm (floored, the outputs
// can overshoot below zero) is the logit, and a softmax with a temperature fitted on held-back
// walks calibrates it: p_i = exp(log(o_i) / t) / sum_j exp(log(o_j) / t).
void softmax(std::span<const float> outputs, double temperature, std::span<float> probability) noexcept {
  double top = -std::numeric_limits<double>::infinity();
  for (const float o : outputs) top = std::max(top, std::log(std::max(static_cast<double>(o), kOutputFloor)) / temperature);
  double sum = 0;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const double e = std::exp(std::log(std::max(static_cast<double>(outputs[i]), kOutputFloor)) / temperature - top);
    probability[i] = static_cast<float>(e);
    sum += e;
  }
  for (std::size_t i = 0; i < outputs.size(); ++i) probability[i] = static_cast<float>(probability[i] / sum);
}

// Mean negative log-likelihood of the labels under softmax(log(outputs) / t).
double mean_nll(const cv::Mat& outputs, const std::vector<int>& labels, double t) {
  double total = 0;
  std::vector<float> p(static_cast<std::size_t>(outputs.cols));
  for (int r = 0; r < outputs.rows; ++r) {
    softmax(std::span<const float>(outputs.ptr<float>(r), p.size()), t, p);
    total -= std::log(std::max(static_cast<double>(p[static_cast<std::size_t>(labels[static_cast<std::size_t>(r)])]),
                               kMinProbability));
  }
  return outputs.rows ? total / outputs.rows : 0.0;
}

double fit_temperature(const cv::Mat& outputs, const std::vector<int>& labels) {
  // Golden-section search on log t; the likelihood is unimodal in t for a fixed set of outputs.
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = std::log(kMinTemperature), b = std::log(kMaxTemperature);
  double c = b - phi * (b - a), d = a + phi * (b - a);
  double fc = mean_nll(outputs, labels, std::exp(c)), fd = mean_nll(outputs, labels, std::exp(d));
  for (int i = 0; i < kTemperatureIterations; ++i) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - phi * (b - a);
      fc = mean_nll(outputs, labels, std::exp(c));
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + phi * (b - a);
      fd = mean_nll(outputs, labels, std::exp(d));
    }
  }
  return std::exp(0.5 * (a + b));
}

// The training copies of a walk. Copy 0 is the walk; with augmentation, copy 1 keeps every other
// point (the path a worker walking twice as fast, or a robot recording half as often, would
// leave) and copy 2 is the walk shifted by up to kShiftM each way (a worker keeping a little
// farther from a shelf, a robot watching from another side), the shift drawn from the walk's
// number so the rows are the same on every run.
constexpr std::size_t kAugmentedCopies = 3;
constexpr double kShiftM = 0.15;
// A recorded point is on the body's near side and noisy: up to this beyond a station's radius
// still counts as at the station.
constexpr double kAtStationSlackM = 0.3;

std::vector<float> training_copy(const std::vector<float>& xy, std::size_t copy, std::size_t walk) {
  if (copy == 0) return xy;
  std::vector<float> out;
  if (copy == 1) {
    for (std::size_t i = 0; i + 1 < xy.size(); i += 4) out.insert(out.end(), {xy[i], xy[i + 1]});
    return out;
  }
  // Two values in [-1, 1) from the walk's number (a multiplicative hash, its top bits).
  const std::uint64_t h = (static_cast<std::uint64_t>(walk) + 1) * 0x9e3779b97f4a7c15ULL;
  const double u = static_cast<double>(h >> 40) / static_cast<double>(1ULL << 24) * 2.0 - 1.0;
  const double v = static_cast<double>((h >> 16) & 0xffffffULL) / static_cast<double>(1ULL << 24) * 2.0 - 1.0;
  out = xy;
  for (std::size_t i = 0; i + 1 < out.size(); i += 2) {
    out[i] = static_cast<float>(out[i] + kShiftM * u);
    out[i + 1] = static_cast<float>(out[i + 1] + kShiftM * v);
  }
  return out;
}

// Whether every point of a prefix is still at the path's first station: the worker has not
// left it, so the path tells nothing but where the operation starts.
bool at_first_station(std::span<const float> xy, const Workstation& first) {
  const double reach = first.radius_m + kAtStationSlackM;
  for (std::size_t i = 0; i + 1 < xy.size(); i += 2)
    if (std::hypot(xy[i] - first.position.x_m, xy[i + 1] - first.position.y_m) > reach) return false;
  return true;
}

// One row of features per prefix of every copy of every path, its label and its target. The
// target is the label one-hot, except while the worker is still at the first station: then it
// is shared equally by the operations that start there (nothing else can be known yet), which
// keeps the network from learning the noise of a standing worker as if it told them apart.
void prefix_rows(const OperationsConfig& config, std::span<const LabelledPath> paths, FeatureEncoding encoding,
                 bool augment, cv::Mat& rows, std::vector<int>& labels, cv::Mat* targets = nullptr) {
  const GridSpec& grid = config.grid;
  const std::size_t features = feature_count(grid, encoding);
  const std::size_t copies = augment ? kAugmentedCopies : 1;
  const int count = static_cast<int>(paths.size() * copies * kProgressSteps);
  const auto classes = static_cast<int>(config.operations.size());
  rows.create(count, static_cast<int>(features), CV_32F);
  if (targets) *targets = cv::Mat::zeros(count, classes, CV_32F);
  labels.clear();
  int r = 0;
  for (std::size_t walk = 0; walk < paths.size(); ++walk) {
    const LabelledPath& p = paths[walk];
    const std::size_t first = config.operations[p.operation].stations.front();
    for (std::size_t copy = 0; copy < copies; ++copy) {
      const std::vector<float> xy = training_copy(p.xy, copy, walk);
      const std::size_t points = xy.size() / 2;
      for (const double f : kPrefixFractions) {
        const std::size_t k = prefix_points(points, f);
        const std::span<const float> prefix = std::span<const float>(xy).first(2 * k);
        path_features(prefix, grid, std::span<float>(rows.ptr<float>(r), features), encoding);
        labels.push_back(static_cast<int>(p.operation));
        if (targets) {
          if (at_first_station(prefix, config.stations[first])) {
            int sharing = 0;
            for (const Operation& op : config.operations) sharing += op.stations.front() == first;
            for (int c = 0; c < classes; ++c)
              if (config.operations[static_cast<std::size_t>(c)].stations.front() == first)
                targets->at<float>(r, c) = 1.0f / static_cast<float>(sharing);
          } else {
            targets->at<float>(r, static_cast<int>(p.operation)) = 1.0f;
          }
        }
        ++r;
      }
    }
  }
}

std::string mismatch(const std::string& path, const std::string& what) { return path + ": " + what; }

}  // namespace

struct OperationRecognizer::Impl {
  ModelInfo info;
  cv::Ptr<cv::ml::ANN_MLP> network;
  cv::Mat input;   // 1 x features, CV_32F: kept between calls
  cv::Mat output;  // 1 x classes, CV_32F
  std::vector<float> probability_scratch;

  void size_buffers() {
    input.create(1, info.layers.front(), CV_32F);
    output.create(1, info.layers.back(), CV_32F);
  }
};

OperationRecognizer::OperationRecognizer(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
OperationRecognizer::~OperationRecognizer() = default;

const ModelInfo& OperationRecognizer::info() const noexcept { return impl_->info; }
std::size_t OperationRecognizer::feature_count() const noexcept {
  return static_cast<std::size_t>(impl_->info.layers.front());
}

Result<std::unique_ptr<OperationRecognizer>> OperationRecognizer::load(const std::string& model_path,
                                                                       const OperationsConfig& config) {
  auto impl = std::make_unique<Impl>();
  ModelInfo& info = impl->info;
  if (!std::ifstream(model_path, std::ios::binary))  // before OpenCV, which logs its own complaint
    return Error::format(Errc::not_found, "%s: cannot open", model_path.c_str());
  try {
    cv::FileStorage fs(model_path, cv::FileStorage::READ);
    if (!fs.isOpened()) return Error::format(Errc::not_found, "%s: cannot open as an OpenCV model file", model_path.c_str());
    const cv::FileNode net = fs[kNetworkNode];
    const cv::FileNode meta = fs[kInfoNode];
    if (net.empty() || meta.empty())
      return Error::format(Errc::config, "%s: not an operations model (needs %s and %s)", model_path.c_str(), kNetworkNode,
                           kInfoNode);
    if (static_cast<int>(meta["format"]) != kFormat)
      return Error::format(Errc::config, "%s: %s.format: expected %d", model_path.c_str(), kInfoNode, kFormat);
    if (!parse_encoding(static_cast<std::string>(meta["encoding"]), info.encoding))
      return Error::format(Errc::config, "%s: %s.encoding: expected occupancy or occupancy_order", model_path.c_str(),
                           kInfoNode);
    const cv::FileNode g = meta["grid"];
    info.grid.origin_x_m = static_cast<double>(g["origin_x_m"]);
    info.grid.origin_y_m = static_cast<double>(g["origin_y_m"]);
    info.grid.cell_m = static_cast<double>(g["cell_m"]);
    info.grid.cols = static_cast<int>(g["cols"]);
    info.grid.rows = static_cast<int>(g["rows"]);
    for (const cv::FileNode& c : meta["classes"]) info.classes.push_back(static_cast<std::string>(c));
    info.temperature = static_cast<double>(meta["temperature"]);
    info.training = static_cast<std::string>(meta["training"]);
    if (!(info.temperature > 0) || !std::isfinite(info.temperature))
      return Error::format(Errc::config, "%s: %s.temperature: expected a positive number", model_path.c_str(), kInfoNode);

    impl->network = cv::ml::ANN_MLP::create();
    impl->network->read(net);
    if (!impl->network->isTrained())
      return Error::format(Errc::config, "%s: %s: not a trained network", model_path.c_str(), kNetworkNode);
    const cv::Mat layers = impl->network->getLayerSizes();
    for (int i = 0; i < static_cast<int>(layers.total()); ++i) info.layers.push_back(layers.at<int>(i));
  } catch (const cv::Exception& e) {
    return Error::format(Errc::config, "%s: %s", model_path.c_str(), e.what());
  }

  // The model must be for these operations on this grid.
  if (info.classes.size() != config.operations.size())
    return Error(Errc::config, mismatch(model_path, "has " + std::to_string(info.classes.size()) + " operations, " +
                                                        config.source + " has " + std::to_string(config.operations.size())));
  for (std::size_t i = 0; i < info.classes.size(); ++i)
    if (info.classes[i] != config.operations[i].name)
      return Error(Errc::config, mismatch(model_path, "operation " + std::to_string(i) + " is '" + info.classes[i] +
                                                          "', " + config.source + " says '" + config.operations[i].name + "'"));
  if (!(info.grid == config.grid))
    return Error(Errc::config, mismatch(model_path, "its grid differs from " + config.source + "'s"));
  if (info.layers.size() < 2 ||
      static_cast<std::size_t>(info.layers.front()) != cobot::feature_count(info.grid, info.encoding) ||
      static_cast<std::size_t>(info.layers.back()) != info.classes.size())
    return Error(Errc::config, mismatch(model_path, "the network's input or output size does not fit the grid and the operations"));
  impl->size_buffers();
  return std::unique_ptr<OperationRecognizer>(new OperationRecognizer(std::move(impl)));
}

Status OperationRecognizer::classify_features(std::span<const float> features, std::span<float> probability) {
  Impl& m = *impl_;
  const std::size_t classes = m.info.classes.size();
  if (features.size() != feature_count()) return Error(Errc::invalid_argument, "classify: wrong feature count");
  if (probability.size() < classes) return Error(Errc::invalid_argument, "classify: probability too short");
  try {
    std::copy(features.begin(), features.end(), m.input.ptr<float>(0));
    m.network->predict(m.input, m.output);
  } catch (const cv::Exception& e) {
    return Error::format(Errc::io, "classify: %s", e.what());
  }
  softmax(std::span<const float>(m.output.ptr<float>(0), classes), m.info.temperature, probability.first(classes));
  return {};
}

Status OperationRecognizer::classify(std::span<const float> xy, std::size_t points, std::span<float> probability) {
  if (points == 0) return Error(Errc::invalid_argument, "classify: an empty path");
  if (2 * points > xy.size()) return Error(Errc::invalid_argument, "classify: fewer coordinates than points");
  Impl& m = *impl_;
  path_features(xy.first(2 * points), m.info.grid,
                std::span<float>(m.input.ptr<float>(0), static_cast<std::size_t>(m.input.cols)), m.info.encoding);
  try {
    m.network->predict(m.input, m.output);
  } catch (const cv::Exception& e) {
    return Error::format(Errc::io, "classify: %s", e.what());
  }
  const std::size_t classes = m.info.classes.size();
  if (probability.size() < classes) return Error(Errc::invalid_argument, "classify: probability too short");
  softmax(std::span<const float>(m.output.ptr<float>(0), classes), m.info.temperature, probability.first(classes));
  return {};
}

Status OperationRecognizer::save(const std::string& path) const {
  const ModelInfo& info = impl_->info;
  try {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    if (!fs.isOpened()) return Error::format(Errc::io, "%s: cannot write", path.c_str());
    fs << kNetworkNode << "{";
    impl_->network->write(fs);
    fs << "}";
    fs << kInfoNode << "{";
    fs << "format" << kFormat;
    fs << "encoding" << std::string(to_string(info.encoding));
    fs << "grid" << "{" << "origin_x_m" << info.grid.origin_x_m << "origin_y_m" << info.grid.origin_y_m << "cell_m"
       << info.grid.cell_m << "cols" << info.grid.cols << "rows" << info.grid.rows << "}";
    fs << "classes" << "[";
    for (const std::string& c : info.classes) fs << c;
    fs << "]";
    fs << "temperature" << info.temperature;
    fs << "training" << info.training;
    fs << "}";
    fs.release();
  } catch (const cv::Exception& e) {
    return Error::format(Errc::io, "%s: %s", path.c_str(), e.what());
  }
  return {};
}

std::size_t prefix_points(std::size_t points, double fraction) noexcept {
  if (points == 0) return 0;
  if (fraction >= 1.0) return points;
  const auto k = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(points) - 1e-9));
  return std::clamp<std::size_t>(k, 1, points);
}

// Builds a recognizer around a trained network (train_recognizer's end).
struct RecognizerAccess {
  static std::unique_ptr<OperationRecognizer> make(ModelInfo info, cv::Ptr<cv::ml::ANN_MLP> network) {
    auto impl = std::make_unique<OperationRecognizer::Impl>();
    impl->info = std::move(info);
    impl->network = std::move(network);
    impl->size_buffers();
    return std::unique_ptr<OperationRecognizer>(new OperationRecognizer(std::move(impl)));
  }
};

Result<std::unique_ptr<OperationRecognizer>> train_recognizer(const OperationsConfig& config,
                                                              std::span<const LabelledPath> training,
                                                              std::span<const LabelledPath> validation,
                                                              const TrainingOptions& options, TrainingReport* report) {
  const std::size_t classes = config.operations.size();
  if (training.empty() || validation.empty()) return Error(Errc::invalid_argument, "train: no training or validation paths");
  for (const auto& set : {training, validation})
    for (const LabelledPath& p : set)
      if (p.operation >= classes || p.points() == 0)
        return Error(Errc::invalid_argument, "train: a path with no points or an unknown operation");
  if (options.hidden.empty() || options.epochs < 1) return Error(Errc::invalid_argument, "train: no hidden layer or epochs");

  ModelInfo info;
  info.encoding = options.encoding;
  info.grid = config.grid;
  for (const Operation& op : config.operations) info.classes.push_back(op.name);
  info.layers.push_back(static_cast<int>(cobot::feature_count(config.grid, options.encoding)));
  info.layers.insert(info.layers.end(), options.hidden.begin(), options.hidden.end());
  info.layers.push_back(static_cast<int>(classes));
  info.training = options.note;

  TrainingReport r;
  const int threads = cv::getNumThreads();
  try {
    cv::setNumThreads(1);
    cv::Mat samples;
    std::vector<int> labels;
    cv::Mat targets;
    prefix_rows(config, training, options.encoding, options.augment, samples, labels, &targets);
    r.samples = static_cast<std::size_t>(samples.rows);

    cv::Ptr<cv::ml::ANN_MLP> network = cv::ml::ANN_MLP::create();
    network->setLayerSizes(cv::Mat(info.layers, true));
    network->setActivationFunction(cv::ml::ANN_MLP::SIGMOID_SYM);
    network->setTrainMethod(cv::ml::ANN_MLP::BACKPROP, options.learning_rate, options.momentum);
    network->setTermCriteria(cv::TermCriteria(cv::TermCriteria::COUNT, options.epochs, 0.0));
    const auto start = std::chrono::steady_clock::now();
    // The features are already 0..1. ANN_MLP would otherwise scale each input by its spread in
    // training, and a cell the training walks hardly touched gets a huge gain: a worker who
    // cuts that corner saturates the network.
    const bool trained = network->train(cv::ml::TrainData::create(samples, cv::ml::ROW_SAMPLE, targets),
                                        cv::ml::ANN_MLP::NO_INPUT_SCALE);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!trained) {
      cv::setNumThreads(threads);
      return Error(Errc::io, "train: the network did not train");
    }

    // The temperature, on every prefix of the validation paths.
    cv::Mat vsamples, voutputs;
    std::vector<int> vlabels;
    prefix_rows(config, validation, options.encoding, false, vsamples, vlabels);
    network->predict(vsamples, voutputs);
    r.validation_samples = static_cast<std::size_t>(vsamples.rows);
    info.temperature = fit_temperature(voutputs, vlabels);
    r.temperature = info.temperature;
    r.validation_nll = mean_nll(voutputs, vlabels, info.temperature);
    std::size_t right = 0, right_whole = 0;
    for (int i = 0; i < voutputs.rows; ++i) {
      const float* o = voutputs.ptr<float>(i);
      const auto best = static_cast<int>(std::max_element(o, o + classes) - o);
      const bool ok = best == vlabels[static_cast<std::size_t>(i)];
      right += ok;
      if (i % static_cast<int>(kProgressSteps) == static_cast<int>(kProgressSteps) - 1) right_whole += ok;
    }
    r.validation_prefix_accuracy = static_cast<double>(right) / voutputs.rows;
    r.validation_accuracy = static_cast<double>(right_whole) / static_cast<double>(validation.size());
    cv::setNumThreads(threads);
    if (report) *report = r;
    return RecognizerAccess::make(std::move(info), std::move(network));
  } catch (const cv::Exception& e) {
    cv::setNumThreads(threads);
    return Error::format(Errc::io, "train: %s", e.what());
  }
}

Result<Evaluation> evaluate(OperationRecognizer& recognizer, std::span<const LabelledPath> paths,
                            double confident_probability) {
  Evaluation e;
  e.classes = recognizer.info().classes;
  const std::size_t classes = e.classes.size();
  e.confusion.assign(classes, std::vector<std::size_t>(classes, 0));
  std::vector<float> p(classes);
  std::size_t right = 0;
  for (const LabelledPath& path : paths) {
    if (path.operation >= classes || path.points() == 0)
      return Error(Errc::invalid_argument, "evaluate: a path with no points or an unknown operation");
    for (std::size_t s = 0; s < kProgressSteps; ++s) {
      const std::size_t k = prefix_points(path.points(), kPrefixFractions[s]);
      const auto start = std::chrono::steady_clock::now();
      if (Status st = recognizer.classify(path.xy, k, p); !st) return st.error();
      const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
      const auto best = static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin());
      e.right_probability[s] += p[path.operation];
      e.confident[s] += p[path.operation] > confident_probability ? 1.0 : 0.0;
      e.step_accuracy[s] += best == path.operation ? 1.0 : 0.0;
      if (s + 1 == kProgressSteps) {
        e.classify_us.push_back(us);
        ++e.confusion[path.operation][best];
        right += best == path.operation;
      }
    }
  }
  e.paths = paths.size();
  if (e.paths) {
    const double n = static_cast<double>(e.paths);
    e.accuracy = static_cast<double>(right) / n;
    for (std::size_t s = 0; s < kProgressSteps; ++s) {
      e.right_probability[s] /= n;
      e.confident[s] /= n;
      e.step_accuracy[s] /= n;
    }
    std::vector<double> sorted = e.classify_us;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    e.median_us = sorted[sorted.size() / 2];
  }
  return e;
}

}  // namespace sen3bot::cobot
