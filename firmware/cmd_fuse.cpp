// `sen3bot fuse`: the camera-laser fusion offline, on a recorded LMS200 capture and a box file
// (the remote detector's replay format), from a laser pose the user gives: what each box would
// place, and why a box placed nobody. For checking a calibration on real recordings.
#include <array>
#include <cmath>
#include <memory_resource>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "box_file.hpp"
#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"
#include "commands.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/lms200/capture_decode.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/people.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kFuseUsage =
    "usage: sen3bot fuse --capture SCANS.s3bcap --boxes BOXES.jsonl [--map MAP.yaml] [--pose X,Y,THETA_DEG]\n"
    "                    [--window S] [--offset S]\n";

struct Scan {
  double t_s = 0;
  std::vector<float> ranges_m;
  double angle_min_rad = 0;
  double increment_rad = 0;
};

bool parse_pose(std::string_view text, nav::Pose2D& pose) {
  const std::size_t last = text.rfind(',');
  if (last == std::string_view::npos) return false;
  msg::Point2D at;
  double theta_deg = 0;
  if (!parse_point_m(text.substr(0, last), at) || !parse_double(text.substr(last + 1), theta_deg) ||
      !std::isfinite(theta_deg))
    return false;
  pose = {at.x_m, at.y_m, theta_deg * std::numbers::pi / 180.0};
  return true;
}

}  // namespace

int fuse_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string capture_path, boxes_path, map_path;
  nav::Pose2D laser;
  double window_s = 0.15;
  double offset_s = 0;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--capture" && has_value) {
      capture_path = argv[++i];
    } else if (arg == "--boxes" && has_value) {
      boxes_path = argv[++i];
    } else if (arg == "--map" && has_value) {
      map_path = argv[++i];
    } else if (arg == "--pose" && has_value) {
      if (!parse_pose(argv[++i], laser)) {
        std::fprintf(err, "sen3bot fuse: --pose: expected X,Y,THETA_DEG, got '%s'\n", argv[i]);
        return 2;
      }
    } else if ((arg == "--window" || arg == "--offset") && has_value) {
      double& value = arg == "--window" ? window_s : offset_s;
      if (!parse_double(argv[++i], value) || !std::isfinite(value) || (arg == "--window" && value < 0)) {
        std::fprintf(err, "sen3bot fuse: %s: expected a number of seconds, got '%s'\n", argv[i - 1], argv[i]);
        return 2;
      }
    } else {
      std::fprintf(err, "sen3bot fuse: unknown or incomplete option '%s'\n%s", argv[i], kFuseUsage);
      return 2;
    }
  }
  if (capture_path.empty() || boxes_path.empty()) {
    std::fprintf(err, "sen3bot fuse: --capture and --boxes are required\n%s", kFuseUsage);
    return 2;
  }
  Result<capture::CaptureFile> capture = capture::CaptureFile::load(capture_path);
  if (!capture) {
    std::fprintf(err, "sen3bot fuse: %s\n", capture.error().c_str());
    return 1;
  }
  std::vector<Scan> scans;
  Result<lms200::CaptureDecodeSummary> decoded = lms200::for_each_scan(*capture, "", [&](const lms200::CapturedScan& s) {
    scans.push_back({s.t_s, {s.ranges_m.begin(), s.ranges_m.end()}, s.angle_min_rad, s.increment_rad});
  });
  if (!decoded) {
    std::fprintf(err, "sen3bot fuse: %s: %s\n", capture_path.c_str(), decoded.error().c_str());
    return 1;
  }
  if (scans.empty()) {
    std::fprintf(err, "sen3bot fuse: %s: no complete LMS200 scan in it\n", capture_path.c_str());
    return 1;
  }
  Result<std::vector<BoxFrame>> frames = load_box_file(boxes_path);
  if (!frames) {
    std::fprintf(err, "sen3bot fuse: %s\n", frames.error().c_str());
    return 2;
  }
  std::optional<nav::OccupancyMap> map;
  if (!map_path.empty()) {
    Result<nav::OccupancyMap> loaded = nav::load_map(map_path);
    if (!loaded) {
      std::fprintf(err, "sen3bot fuse: %s\n", loaded.error().c_str());
      return 2;
    }
    map = std::move(*loaded);
  }
  nav::FusionConfig config;
  config.match_window_s = window_s;
  std::pmr::monotonic_buffer_resource arena;
  nav::PeopleFusion fusion;
  if (Status s = fusion.init(config, {}, map ? &*map : nullptr, msg::ScanMessage::kMaxBeams, arena); !s) {
    std::fprintf(err, "sen3bot fuse: %s\n", s.error().c_str());
    return 1;
  }
  std::size_t placed = 0;
  for (const BoxFrame& frame : *frames) {
    // The scan nearest the frame in time; the fusion judges whether it is near enough.
    const double t = frame.t_s + offset_s;
    const Scan* nearest = &scans.front();
    for (const Scan& s : scans)
      if (std::abs(s.t_s - t) < std::abs(nearest->t_s - t)) nearest = &s;
    msg::PersonDetections detections = frame.detections;
    detections.capture_ns = hal::from_seconds(t);
    const msg::ScanView view{nearest->ranges_m, static_cast<float>(nearest->angle_min_rad),
                             static_cast<float>(nearest->increment_rad), 0.01f, 80.0f,
                             hal::from_seconds(nearest->t_s)};
    std::array<std::uint64_t, nav::kBoxVerdicts> before{};
    for (std::size_t v = 0; v < nav::kBoxVerdicts; ++v) before[v] = fusion.count(static_cast<nav::BoxVerdict>(v));
    std::array<nav::PersonFix, msg::PersonDetections::kMax> fixes{};
    const std::size_t n = fusion.fuse(view, laser, detections, fixes);
    placed += n;
    json::FileSink sink(out);
    json::Writer w(sink, json::Style::spaced);
    w.begin_object().key("t_s").fixed_or_null(frame.t_s, 6).key("scan_t_s").fixed_or_null(nearest->t_s, 6).key("people").begin_array();
    for (std::size_t i = 0; i < n; ++i) {
      const nav::PersonFix& f = fixes[i];
      w.begin_object()
          .member_uint32("box", f.box)
          .key("x_m").fixed_or_null(f.x_m, 3)
          .key("y_m").fixed_or_null(f.y_m, 3)
          .key("range_m").fixed_or_null(f.range_m, 3)
          .key("width_m").fixed_or_null(f.width_m, 3)
          .member_uint32("points", f.points)
          .end_object();
    }
    w.end_array().key("boxes").begin_object();
    for (std::size_t v = 0; v < nav::kBoxVerdicts; ++v) {
      const std::uint64_t k = fusion.count(static_cast<nav::BoxVerdict>(v)) - before[v];
      if (k != 0) w.member_uint64(nav::to_string(static_cast<nav::BoxVerdict>(v)), k);
    }
    w.end_object().end_object();
    std::fputc('\n', out);
  }
  std::fprintf(err, "%zu scans, %zu frames, %zu people placed", scans.size(), frames->size(), placed);
  for (std::size_t v = 0; v < nav::kBoxVerdicts; ++v)
    std::fprintf(err, ", %llu %s", static_cast<unsigned long long>(fusion.count(static_cast<nav::BoxVerdict>(v))),
                 nav::to_string(static_cast<nav::BoxVerdict>(v)));
  std::fprintf(err, "\n");
  return 0;
}

}  // namespace sen3bot::firmware
