// The shipped recognizer on workers of the held-out walking style (seeds of the test stream,
// never trained on): the targets of docs/cobot/recognition.md. Also loading errors, classify's
// argument checks, and that training is reproducible.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "sen3bot/cobot/recognizer.hpp"
#include "sen3bot/sim/cobot/workers.hpp"

#ifndef SEN3BOT_HELD_OUT_WALKS
#define SEN3BOT_HELD_OUT_WALKS 20
#endif

namespace sen3bot::cobot {
namespace {

const std::string kOperations = SEN3BOT_SOURCE_DIR "/config/cobot/operations.yaml";
const std::string kModel = SEN3BOT_SOURCE_DIR "/config/cobot/operations-model.yaml.gz";
// Not the experiment's default seed, so the test and the documented run are different walks.
constexpr std::uint64_t kTestSeed = 20260;

class Recognizer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    Result<OperationsConfig> c = load_operations(kOperations);
    ASSERT_TRUE(c.ok()) << c.error().c_str();
    config_ = new OperationsConfig(std::move(*c));
    Result<nav::OccupancyMap> m = nav::load_map(config_->map_path);
    ASSERT_TRUE(m.ok()) << m.error().c_str();
    map_ = new nav::OccupancyMap(std::move(*m));
  }
  static void TearDownTestSuite() {
    delete map_;
    delete config_;
  }
  std::unique_ptr<WorkerSimulator> workers() {
    Result<std::unique_ptr<WorkerSimulator>> w = WorkerSimulator::create(*config_, *map_);
    EXPECT_TRUE(w.ok());
    return w.ok() ? std::move(*w) : nullptr;
  }
  std::unique_ptr<OperationRecognizer> shipped() {
    Result<std::unique_ptr<OperationRecognizer>> r = OperationRecognizer::load(kModel, *config_);
    EXPECT_TRUE(r.ok()) << r.error().c_str();
    return r.ok() ? std::move(*r) : nullptr;
  }
  static OperationsConfig* config_;
  static nav::OccupancyMap* map_;
};
OperationsConfig* Recognizer::config_ = nullptr;
nav::OccupancyMap* Recognizer::map_ = nullptr;

TEST_F(Recognizer, ShippedModelMeetsTheTargetsOnHeldOutWorkers) {
  std::unique_ptr<WorkerSimulator> sim = workers();
  std::unique_ptr<OperationRecognizer> model = shipped();
  ASSERT_TRUE(sim && model);
  DatasetSpec spec;
  spec.styles = std::span<const WorkerStyle>(&held_out_style(), 1);
  spec.per_operation = SEN3BOT_HELD_OUT_WALKS;
  spec.seed = kTestSeed;
  spec.purpose = kTestSeeds;
  Result<std::vector<LabelledPath>> paths = generate_paths(*sim, spec);
  ASSERT_TRUE(paths.ok()) << paths.error().c_str();
  ASSERT_EQ(paths->size(), SEN3BOT_HELD_OUT_WALKS * config_->operations.size());
  Result<Evaluation> e = evaluate(*model, *paths, 0.95);
  ASSERT_TRUE(e.ok()) << e.error().c_str();
  EXPECT_GE(e->accuracy, 0.97);
  EXPECT_GE(e->confident[5], 0.95) << "right operation above 0.95 at 60 % of the path";
  // The probabilities sharpen as the path grows.
  EXPECT_GT(e->right_probability[9], e->right_probability[0] + 0.2);
  EXPECT_GT(e->right_probability[5], e->right_probability[1]);
  // Every operation is recognised on most of its walks.
  for (std::size_t op = 0; op < e->confusion.size(); ++op)
    EXPECT_GE(e->confusion[op][op] * 10, 9u * SEN3BOT_HELD_OUT_WALKS) << e->classes[op];
}

TEST_F(Recognizer, ShippedModelDescribesItself) {
  std::unique_ptr<OperationRecognizer> model = shipped();
  ASSERT_TRUE(model);
  const ModelInfo& info = model->info();
  EXPECT_EQ(info.encoding, FeatureEncoding::occupancy_order);
  EXPECT_EQ(info.grid, config_->grid);
  ASSERT_EQ(info.classes.size(), config_->operations.size());
  for (std::size_t i = 0; i < info.classes.size(); ++i) EXPECT_EQ(info.classes[i], config_->operations[i].name);
  EXPECT_EQ(model->feature_count(), feature_count(config_->grid, FeatureEncoding::occupancy_order));
  EXPECT_GT(info.temperature, 0.0);
  EXPECT_NE(info.training.find("seed"), std::string::npos);
  std::ifstream f(kModel, std::ios::binary | std::ios::ate);
  EXPECT_LT(static_cast<long>(f.tellg()), 1024L * 1024L) << "the model file stays under 1 MB";
}

TEST_F(Recognizer, ClassifyChecksItsArguments) {
  std::unique_ptr<OperationRecognizer> model = shipped();
  ASSERT_TRUE(model);
  std::vector<float> p(model->operations());
  const std::vector<float> xy{1.6f, 7.05f, 1.7f, 7.0f};
  EXPECT_FALSE(model->classify(xy, 0, p).ok());
  EXPECT_FALSE(model->classify(xy, 3, p).ok());
  std::vector<float> short_p(model->operations() - 1);
  EXPECT_FALSE(model->classify(xy, 2, short_p).ok());
  ASSERT_TRUE(model->classify(xy, 2, p).ok());
  EXPECT_NEAR(std::accumulate(p.begin(), p.end(), 0.0), 1.0, 1e-5);
  std::vector<float> features(model->feature_count() + 1);
  EXPECT_FALSE(model->classify_features(features, p).ok());
}

TEST_F(Recognizer, LoadRefusesAModelForOtherOperations) {
  OperationsConfig renamed = *config_;
  renamed.operations[1].name = "unpacking";
  Result<std::unique_ptr<OperationRecognizer>> r = OperationRecognizer::load(kModel, renamed);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(std::string(r.error().c_str()).find("operation 1 is 'returns'"), std::string::npos) << r.error().c_str();
  OperationsConfig coarser = *config_;
  coarser.grid.cell_m = 1.0;
  r = OperationRecognizer::load(kModel, coarser);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(std::string(r.error().c_str()).find("grid"), std::string::npos) << r.error().c_str();
  EXPECT_EQ(OperationRecognizer::load("/nonexistent/model.yaml.gz", *config_).error().code(), Errc::not_found);
  r = OperationRecognizer::load(kOperations, *config_);  // YAML, but no model in it
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code(), Errc::config);
  EXPECT_NE(std::string(r.error().c_str()).find(kOperations), std::string::npos) << r.error().c_str();
  const std::string other = "/tmp/sen3bot-not-a-model-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(other) << "%YAML:1.0\n---\nsomething: 1\n";
  r = OperationRecognizer::load(other, *config_);
  ::unlink(other.c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(std::string(r.error().c_str()).find("not an operations model"), std::string::npos) << r.error().c_str();
}

std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

TEST_F(Recognizer, TrainingIsReproducible) {
  std::unique_ptr<WorkerSimulator> sim = workers();
  ASSERT_TRUE(sim);
  DatasetSpec spec;
  spec.styles = training_styles();
  spec.per_operation = 4;
  Result<std::vector<LabelledPath>> train = generate_paths(*sim, spec);
  spec.purpose = kValidationSeeds;
  spec.per_operation = 2;
  Result<std::vector<LabelledPath>> validation = generate_paths(*sim, spec);
  ASSERT_TRUE(train.ok() && validation.ok());
  TrainingOptions options;
  options.hidden = {8};
  options.epochs = 3;
  const std::string dir = "/tmp/sen3bot-recognizer-" + std::to_string(::getpid());
  std::vector<std::string> files;
  for (int run = 0; run < 2; ++run) {
    TrainingReport report;
    Result<std::unique_ptr<OperationRecognizer>> r = train_recognizer(*config_, *train, *validation, options, &report);
    ASSERT_TRUE(r.ok()) << r.error().c_str();
    EXPECT_EQ(report.samples, 3 * train->size() * kProgressSteps);  // as walked, thinned, shifted
    EXPECT_GT(report.temperature, 0.0);
    files.push_back(dir + "-" + std::to_string(run) + ".yaml.gz");
    ASSERT_TRUE((*r)->save(files.back()).ok());
    // What was saved loads back and classifies the same.
    Result<std::unique_ptr<OperationRecognizer>> loaded = OperationRecognizer::load(files.back(), *config_);
    ASSERT_TRUE(loaded.ok()) << loaded.error().c_str();
    std::vector<float> a((*r)->operations()), b(a.size());
    ASSERT_TRUE((*r)->classify((*validation)[0].xy, (*validation)[0].points(), a).ok());
    ASSERT_TRUE((*loaded)->classify((*validation)[0].xy, (*validation)[0].points(), b).ok());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-5f);
  }
  const std::string first = read_bytes(files[0]);
  EXPECT_GT(first.size(), 1000u);
  EXPECT_EQ(first, read_bytes(files[1]));
  for (const std::string& f : files) ::unlink(f.c_str());
}

}  // namespace
}  // namespace sen3bot::cobot
