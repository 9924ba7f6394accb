// sen3bot camera probe: connect to an RTSP camera, decode N frames, report what arrived.
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <sys/stat.h>
#include <thread>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "commands.hpp"
#include "sen3bot/camera/camera.hpp"

namespace sen3bot::firmware {
namespace {

constexpr const char* kCameraUsage =
    "usage: sen3bot camera probe URL [--transport tcp|udp] [--frames N] [--save DIR] [--timeout S]\n"
    "  URL is rtsp://[user:pass@]host[:port]/path\n";

bool parse_positive(const char* text, double& out) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text, &end);
  if (errno != 0 || end == text || *end != '\0' || !(v > 0)) return false;
  out = v;
  return true;
}

void json_escape(std::FILE* out, std::string_view s) {
  for (char c : s) {
    if (c == '"' || c == '\\') std::fputc('\\', out);
    if (static_cast<unsigned char>(c) < 0x20) continue;
    std::fputc(c, out);
  }
}

int probe(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc < 1) {
    std::fputs(kCameraUsage, err);
    return 2;
  }
  camera::CameraConfig config;
  config.rtsp.url = argv[0];
  double frames_wanted = 30;
  double timeout_s = 20;
  std::string save_dir;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--transport" && has_value) {
      const std::string_view t = argv[++i];
      if (t == "tcp") {
        config.rtsp.transport = camera::RtpTransport::tcp_interleaved;
      } else if (t == "udp") {
        config.rtsp.transport = camera::RtpTransport::udp;
      } else {
        std::fprintf(err, "sen3bot camera probe: --transport must be tcp or udp\n");
        return 2;
      }
    } else if (arg == "--frames" && has_value) {
      if (!parse_positive(argv[++i], frames_wanted)) {
        std::fprintf(err, "sen3bot camera probe: --frames needs a positive number\n");
        return 2;
      }
    } else if (arg == "--timeout" && has_value) {
      if (!parse_positive(argv[++i], timeout_s)) {
        std::fprintf(err, "sen3bot camera probe: --timeout needs a positive number of seconds\n");
        return 2;
      }
    } else if (arg == "--save" && has_value) {
      save_dir = argv[++i];
      ::mkdir(save_dir.c_str(), 0755);
    } else {
      std::fprintf(err, "sen3bot camera probe: unknown option '%s'\n%s", argv[i], kCameraUsage);
      return 2;
    }
  }
  if (std::string_view(config.rtsp.url).starts_with("onvif://")) {
    std::fprintf(err, "sen3bot camera probe: onvif:// URLs are not supported by this build; give the rtsp:// URL\n");
    return 2;
  }
  hal::PosixClock clock;
  auto cam = camera::Camera::create(config, clock);
  if (!cam) {
    std::fprintf(err, "sen3bot camera probe: %s\n", cam.error().c_str());
    return 2;
  }
  (void)(*cam)->start();
  const auto start = std::chrono::steady_clock::now();
  const auto deadline = start + std::chrono::duration<double>(timeout_s);
  std::uint64_t seen = 0;
  std::uint64_t first_seq = 0;
  hal::Nanos first_ns = 0;
  hal::Nanos last_ns = 0;
  bool described = false;
  while (std::chrono::steady_clock::now() < deadline && seen < static_cast<std::uint64_t>(frames_wanted)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (!described) {
      const auto status = (*cam)->status();
      if (status.state == camera::ClientState::playing) {
        described = true;
        std::fprintf(out, "{\"event\":\"playing\",\"codec\":\"%s\",\"transport\":\"%s\",\"setup_url\":\"",
                     camera::to_string(status.stream.codec), camera::to_string(status.stream.transport));
        json_escape(out, status.stream.setup_url);
        std::fprintf(out, "\",\"session_timeout_s\":%d}\n", status.stream.session_timeout_s);
        std::fflush(out);
      }
    }
    camera::FrameHandle frame = (*cam)->frames().acquire_latest();
    if (!frame || frame.ref().sequence == seen) continue;
    const camera::FrameRef& ref = frame.ref();
    if (first_seq == 0) {
      first_seq = ref.sequence;
      first_ns = ref.decoded_ns;
    }
    seen = ref.sequence;
    last_ns = ref.decoded_ns;
    if (!save_dir.empty()) {
      const cv::Mat image(static_cast<int>(ref.height_px), static_cast<int>(ref.width_px),
                          ref.format == camera::PixelFormat::gray8 ? CV_8UC1 : CV_8UC3, const_cast<std::uint8_t*>(ref.data),
                          ref.stride_bytes);
      char name[64];
      std::snprintf(name, sizeof name, "/frame_%06llu.png", static_cast<unsigned long long>(ref.sequence));
      cv::imwrite(save_dir + name, image);
    }
  }
  const auto status = (*cam)->status();
  (*cam)->stop();
  const std::uint64_t decoded = status.decoder.frames_decoded;
  const std::uint64_t dropped = status.decoder.decode_errors + status.decoder.no_free_slot +
                                status.depacketizer.frames_dropped_damaged + status.depacketizer.frames_dropped_no_idr +
                                status.depacketizer.frames_dropped_oversize;
  const double span_s = static_cast<double>(last_ns - first_ns) / 1e9;
  const double fps = seen > first_seq && span_s > 0 ? static_cast<double>(seen - first_seq) / span_s : 0.0;
  if (decoded == 0 && !status.last_error.empty()) {
    std::fprintf(err, "sen3bot camera probe: no frame decoded: %s\n", status.last_error.c_str());
  }
  std::fprintf(out,
               "{\"codec\":\"%s\",\"width\":%u,\"height\":%u,\"transport\":\"%s\",\"frames_decoded\":%llu,"
               "\"frames_dropped\":%llu,\"fps\":%.2f,\"latency_ms_p50\":%.2f,\"rtp_packets\":%llu,\"rtp_lost\":%llu}\n",
               camera::to_string(status.stream.codec), status.decoder.source_width_px, status.decoder.source_height_px,
               camera::to_string(status.stream.transport), static_cast<unsigned long long>(decoded),
               static_cast<unsigned long long>(dropped), fps, status.latency_ms_p50,
               static_cast<unsigned long long>(status.rtsp.rtp_packets), static_cast<unsigned long long>(status.rtsp.rtp_lost));
  return decoded > 0 ? 0 : 1;
}

}  // namespace

int camera_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc >= 1 && std::string_view(argv[0]) == "probe") return probe(argc - 1, argv + 1, out, err);
  std::fputs(kCameraUsage, err);
  return 2;
}

}  // namespace sen3bot::firmware
