// The QR tag reader's time per 1280 x 720 camera frame, on a simulated frame with an operator's
// tag at 1 m (TagSceneRenderer, the robot's calibration): the whole frame and a 512 px region
// around the tag, each search mode, an empty frame; and the renderer's own time per frame.
// docs/cobot/tags.md gives the numbers.
#include <benchmark/benchmark.h>

#include <vector>

#include "sen3bot/cobot/qr_reader.hpp"
#include "sen3bot/sim/cobot/tag_scene.hpp"

namespace {

using namespace sen3bot;

constexpr std::uint32_t kWidth = 1280;
constexpr std::uint32_t kHeight = 720;

struct Scene {
  std::vector<std::uint8_t> pixels = std::vector<std::uint8_t>(kWidth * kHeight * 3);
  camera::FrameRef ref;
  double u_px = 0.0;
  double v_px = 0.0;
  bool ok = false;

  explicit Scene(bool with_tag) {
    cobot::TagSceneRenderer renderer;
    if (!renderer.init(nav::CameraCalibration{}, 1)) return;
    const cobot::SceneTag tag{1.0, 0.05, 0.05, 0.3, cobot::Tag{42, msg::TagSide::front}};
    ok = renderer.render(with_tag ? std::span<const cobot::SceneTag>(&tag, 1) : std::span<const cobot::SceneTag>(),
                         pixels, kWidth * 3, camera::PixelFormat::bgr8) &&
         renderer.centre_px(tag, u_px, v_px);
    ref = camera::FrameRef{pixels.data(), kWidth, kHeight, kWidth * 3, camera::PixelFormat::bgr8, 1, 0, 0, 0};
  }
};

// range(0): 0 whole frame, 1 a 512 x 512 ROI on the tag; range(1): 0 first_code, 1 every_code;
// range(2): 1 the tag is in the frame, 0 an empty scene.
void BM_QrRead(benchmark::State& state) {
  static const Scene with_tag(true);
  static const Scene empty(false);
  const Scene& scene = state.range(2) != 0 ? with_tag : empty;
  if (!scene.ok) {
    state.SkipWithError("the scene could not be rendered");
    return;
  }
  cobot::QrReaderConfig config;
  config.search = state.range(1) != 0 ? cobot::QrReaderConfig::Search::every_code
                                      : cobot::QrReaderConfig::Search::first_code;
  cobot::QrReader reader;
  if (!reader.init(kWidth, kHeight, config)) {
    state.SkipWithError("init failed");
    return;
  }
  const cobot::PixelRect roi{static_cast<int>(with_tag.u_px) - 256, static_cast<int>(with_tag.v_px) - 256, 512, 512};
  msg::TagFrame out;
  for (auto _ : state) {
    const std::size_t n = state.range(0) != 0 ? reader.read(scene.ref, roi, out) : reader.read(scene.ref, out);
    benchmark::DoNotOptimize(n);
  }
  state.counters["tags_per_frame"] = static_cast<double>(reader.tags_read()) / static_cast<double>(reader.frames());
}
BENCHMARK(BM_QrRead)
    ->ArgNames({"roi", "every_code", "tag"})
    ->Args({0, 0, 1})
    ->Args({1, 0, 1})
    ->Args({0, 1, 1})
    ->Args({1, 1, 1})
    ->Args({0, 0, 0})
    ->Args({1, 0, 0})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

void BM_TagSceneRender(benchmark::State& state) {
  cobot::TagSceneRenderer renderer;
  cobot::SceneOptions options;
  options.motion_blur_px = static_cast<double>(state.range(0));
  if (!renderer.init(nav::CameraCalibration{}, 1, options)) {
    state.SkipWithError("init failed");
    return;
  }
  std::vector<std::uint8_t> pixels(kWidth * kHeight * 3);
  const cobot::SceneTag tags[] = {{1.0, 0.05, 0.05, 0.3, cobot::Tag{42, msg::TagSide::front}},
                                  {0.8, -0.3, 0.05, -0.2, cobot::Tag{43, msg::TagSide::back}}};
  for (auto _ : state) {
    benchmark::DoNotOptimize(renderer.render(tags, pixels, kWidth * 3, camera::PixelFormat::bgr8));
  }
}
// range(0): the motion blur's length in pixels (0: none).
BENCHMARK(BM_TagSceneRender)->ArgName("motion_px")->Arg(0)->Arg(4)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
