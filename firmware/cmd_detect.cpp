// `sen3bot detect`: the on-board people detector (OpenCV's HOG people coefficients) on an
// image file, as the firmware runs it on camera frames: the boxes as JSON, drawn with --png.
#include <algorithm>
#include <chrono>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"
#include "commands.hpp"
#include "sen3bot/image/image_file.hpp"
#include "sen3bot/detector/hog.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kDetectUsage =
    "usage: sen3bot detect --image FILE [--scale S] [--threshold T] [--repeat N] [--png FILE]\n";

}  // namespace

int detect_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string image_path, png;
  detector::HogConfig config;
  std::uint32_t repeat = 1;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--image" && has_value) {
      image_path = argv[++i];
    } else if (arg == "--png" && has_value) {
      png = argv[++i];
    } else if ((arg == "--scale" || arg == "--threshold") && has_value) {
      double& value = arg == "--scale" ? config.scale : config.hit_threshold;
      if (!parse_double(argv[++i], value)) {
        std::fprintf(err, "sen3bot detect: %s: expected a number, got '%s'\n", argv[i - 1], argv[i]);
        return 2;
      }
    } else if (arg == "--repeat" && has_value) {
      if (!parse_u32(argv[++i], repeat) || repeat == 0 || repeat > 10000) {
        std::fprintf(err, "sen3bot detect: --repeat: expected 1..10000, got '%s'\n", argv[i]);
        return 2;
      }
    } else {
      std::fprintf(err, "sen3bot detect: unknown or incomplete option '%s'\n%s", argv[i], kDetectUsage);
      return 2;
    }
  }
  if (image_path.empty()) {
    std::fprintf(err, "sen3bot detect: --image is required\n%s", kDetectUsage);
    return 2;
  }
  image::Image file;
  if (Status s = image::read_image(image_path, 3, file); !s) {
    std::fprintf(err, "sen3bot detect: cannot read it as an image: %s\n", s.error().c_str());
    return 1;
  }
  const cv::Mat image(static_cast<int>(file.height_px), static_cast<int>(file.width_px), CV_8UC3, file.pixels.data());
  detector::HogPeopleDetector hog;
  if (Status s = hog.init(config, static_cast<std::uint32_t>(image.cols), static_cast<std::uint32_t>(image.rows)); !s) {
    std::fprintf(err, "sen3bot detect: %s: %s\n", image_path.c_str(), s.error().c_str());
    return 2;
  }
  const detector::ImageView view{image.data, static_cast<std::uint32_t>(image.cols),
                                 static_cast<std::uint32_t>(image.rows), static_cast<std::uint32_t>(image.step[0]), 3};
  detector::Detections found;
  // The first call builds OpenCV's caches; the time is the median of the rest (or the one).
  std::vector<double> times_ms;
  for (std::uint32_t k = 0; k < repeat; ++k) {
    const auto begin = std::chrono::steady_clock::now();
    if (Status s = hog.detect(view, found); !s) {
      std::fprintf(err, "sen3bot detect: %s\n", s.error().c_str());
      return 1;
    }
    times_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
  }
  if (times_ms.size() > 1) times_ms.erase(times_ms.begin());
  std::sort(times_ms.begin(), times_ms.end());
  const double median_ms = times_ms[times_ms.size() / 2];
  json::FileSink sink(out);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .member("image", image_path)
      .member_int64("width_px", image.cols)
      .member_int64("height_px", image.rows)
      .key("scale").fixed_or_null(config.scale, 3)
      .key("threshold").fixed_or_null(config.hit_threshold, 3)
      .key("time_ms").fixed_or_null(median_ms, 3)
      .member_uint32("runs", repeat)
      .key("people").begin_array();
  for (std::size_t b = 0; b < found.count; ++b) {
    const detector::Box& box = found.boxes[b];
    w.begin_object()
        .key("u0").fixed_or_null(box.u0, 1)
        .key("v0").fixed_or_null(box.v0, 1)
        .key("u1").fixed_or_null(box.u1, 1)
        .key("v1").fixed_or_null(box.v1, 1)
        .key("confidence").fixed_or_null(box.confidence, 3)
        .end_object();
  }
  w.end_array().end_object();
  std::fputc('\n', out);
  if (!png.empty()) {
    cv::Mat drawn = image.clone();
    for (std::size_t b = 0; b < found.count; ++b) {
      const detector::Box& box = found.boxes[b];
      const cv::Point top_left(static_cast<int>(box.u0), static_cast<int>(box.v0));
      cv::rectangle(drawn, top_left, cv::Point(static_cast<int>(box.u1), static_cast<int>(box.v1)),
                    cv::Scalar(0, 200, 0), 2);
      char label[32];
      std::snprintf(label, sizeof label, "person %.2f", box.confidence);
      cv::putText(drawn, label, top_left + cv::Point(2, 14), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 200, 0), 1);
    }
    if (Status s = image::write_png(png, drawn.data, static_cast<std::uint32_t>(drawn.cols),
                                     static_cast<std::uint32_t>(drawn.rows), drawn.step, 3);
        !s) {
      std::fprintf(err, "sen3bot detect: cannot write %s: %s\n", png.c_str(), s.error().c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace sen3bot::firmware
