// sen3bot camera probe: connect to an RTSP camera, decode N frames, report what arrived.
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <sys/stat.h>
#include <thread>

#include "cli_util.hpp"
#include "commands.hpp"
#include "sen3bot/camera/camera.hpp"
#include "sen3bot/image/image_file.hpp"
#include "sen3bot/camera/onvif_client.hpp"
#include "sen3bot/camera/rtsp_url.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::firmware {
namespace {

constexpr const char* kCameraUsage =
    "usage: sen3bot camera discover [--timeout S]\n"
    "       sen3bot camera probe URL [--transport tcp|udp] [--frames N] [--save DIR] [--timeout S]\n"
    "       sen3bot camera ptz onvif://user:pass@host[:port] --pan P --tilt T --zoom Z --seconds S\n"
    "  URL is rtsp://[user:pass@]host[:port]/path or onvif://user:pass@host[:port]\n";

// onvif://user:pass@host[:port] (port 80 by default) as an ONVIF client configuration.
Result<camera::onvif::OnvifConfig> parse_onvif_url(std::string_view url) {
  constexpr std::string_view kScheme = "onvif://";
  if (!url.starts_with(kScheme)) return Error(Errc::invalid_argument, "expected onvif://user:pass@host[:port]");
  const std::string_view rest = url.substr(kScheme.size());
  std::string_view authority = rest.substr(0, rest.find('/'));
  if (const std::size_t at = authority.rfind('@'); at != std::string_view::npos) authority.remove_prefix(at + 1);
  const bool has_port = authority.find(':') != std::string_view::npos;
  const std::string as_rtsp = "rtsp://" + std::string(rest);
  auto parsed = camera::parse_rtsp_url(as_rtsp);
  if (!parsed) return parsed.error();
  camera::onvif::OnvifConfig config;
  config.host = parsed->host;
  config.port = has_port ? parsed->port : 80;
  config.credentials = {parsed->user, parsed->password};
  return config;
}

// Asks the device for its RTSP URI (host rewritten to the one we reach it on).
Result<std::string> onvif_stream_url(std::string_view url) {
  auto config = parse_onvif_url(url);
  if (!config) return config.error();
  const camera::Credentials creds = config->credentials;
  auto client = camera::onvif::OnvifClient::create(*config);
  if (!client) return client.error();
  if (auto s = (*client)->connect(); !s) return s.error();
  auto profiles = (*client)->profiles();
  if (!profiles) return profiles.error();
  const camera::onvif::Profile* p = camera::onvif::choose_profile(*profiles, "H264", 1280, 720);
  if (p == nullptr) return Error(Errc::not_found, "no media profile");
  auto uri = (*client)->stream_uri(p->token);
  if (!uri) return uri.error();
  // The RTSP URI carries no credentials: authenticate RTSP with the ONVIF ones.
  std::string out = *uri;
  if (!creds.user.empty() && out.starts_with("rtsp://") && out.find('@') == std::string::npos) {
    out.insert(7, creds.user + ":" + creds.password + "@");
  }
  return out;
}

bool parse_positive(const char* text, double& out) {
  double v = 0;
  if (!parse_double(text, v) || !(v > 0)) return false;
  out = v;
  return true;
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
      const bool whole = parse_positive(argv[++i], frames_wanted) && frames_wanted == std::floor(frames_wanted);
      if (!whole || frames_wanted > 1e9) {
        std::fprintf(err, "sen3bot camera probe: --frames needs a whole number from 1 to 1e9\n");
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
    auto rtsp = onvif_stream_url(config.rtsp.url);
    if (!rtsp) {
      std::fprintf(err, "sen3bot camera probe: ONVIF: %s\n", rtsp.error().c_str());
      return 1;
    }
    config.rtsp.url = *rtsp;
  }
  // The camera decodes exactly the frames asked for; the loop waits for its own count, which
  // the pool's sequence numbers (sampled, and ahead of the status) cannot give.
  const auto wanted = static_cast<std::uint64_t>(frames_wanted);
  config.decode_limit_frames = wanted;
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
  for (;;) {
    const camera::CameraStatus status = (*cam)->status();
    if (!described && status.state == camera::ClientState::playing) {
      described = true;
      json::FileSink sink(out);
      json::Writer w(sink);
      w.begin_object()
          .member("event", "playing")
          .member("codec", camera::to_string(status.stream.codec))
          .member("transport", camera::to_string(status.stream.transport))
          .member("setup_url", status.stream.setup_url)
          .member_int64("session_timeout_s", status.stream.session_timeout_s)
          .end_object();
      std::fputc('\n', out);
      std::fflush(out);
    }
    if (status.decoder.frames_decoded >= wanted || status.failed() || std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
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
      char name[64];
      std::snprintf(name, sizeof name, "/frame_%06llu.png", static_cast<unsigned long long>(ref.sequence));
      (void)image::write_png(save_dir + name, ref.data, ref.width_px, ref.height_px, ref.stride_bytes,
                              static_cast<int>(camera::bytes_per_pixel(ref.format)));
    }
  }
  (*cam)->stop();
  // After the thread has stopped: the counts are final.
  const camera::CameraStatus status = (*cam)->status();
  const std::uint64_t decoded = status.decoder.frames_decoded;
  const std::uint64_t dropped = status.decoder.decode_errors + status.decoder.no_free_slot +
                                status.depacketizer.frames_dropped_damaged + status.depacketizer.frames_dropped_no_idr +
                                status.depacketizer.frames_dropped_oversize;
  const double span_s = static_cast<double>(last_ns - first_ns) / 1e9;
  const double fps = seen > first_seq && span_s > 0 ? static_cast<double>(seen - first_seq) / span_s : 0.0;
  if (status.failed()) {
    std::fprintf(err, "sen3bot camera probe: %s (not retrying)\n", status.last_error.c_str());
  } else if (decoded < wanted) {
    std::fprintf(err, "sen3bot camera probe: %llu of %llu frames decoded in %.1f s%s%s\n",
                 static_cast<unsigned long long>(decoded), static_cast<unsigned long long>(wanted), timeout_s,
                 status.last_error.empty() ? "" : "; last error: ", status.last_error.c_str());
  }
  json::FileSink sink(out);
  json::Writer w(sink);
  w.begin_object()
      .member("codec", camera::to_string(status.stream.codec))
      .member_uint32("width", status.decoder.source_width_px)
      .member_uint32("height", status.decoder.source_height_px)
      .member("transport", camera::to_string(status.stream.transport))
      .member_uint64("frames_decoded", decoded)
      .member_uint64("frames_dropped", dropped)
      .key("fps").fixed_or_null(fps, 2)
      .key("latency_ms_p50").fixed_or_null(status.latency_ms_p50, 2)
      .member_uint64("rtp_packets", status.rtsp.rtp_packets)
      .member_uint64("rtp_lost", status.rtsp.rtp_lost)
      .end_object();
  std::fputc('\n', out);
  return decoded > 0 && !status.failed() ? 0 : 1;
}

int discover_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  camera::onvif::DiscoveryOptions options;
  for (int i = 0; i < argc; ++i) {
    double seconds = 0;
    if (std::string_view(argv[i]) == "--timeout" && i + 1 < argc && parse_positive(argv[i + 1], seconds)) {
      options.timeout_ms = static_cast<int>(seconds * 1000);
      ++i;
    } else {
      std::fputs(kCameraUsage, err);
      return 2;
    }
  }
  auto found = camera::onvif::discover(options);
  if (!found) {
    std::fprintf(err, "sen3bot camera discover: %s\n", found.error().c_str());
    return 1;
  }
  json::FileSink sink(out);
  json::Writer w(sink);
  w.begin_array();
  for (const auto& m : *found) {
    w.line(2).begin_object().member("endpoint", m.endpoint).key("xaddrs").begin_array();
    for (const auto& xaddr : m.xaddrs) w.string(xaddr);
    w.end_array().member("types", m.types).member("scopes", m.scopes).end_object();
  }
  if (!found->empty()) w.line(0);
  w.end_array();
  std::fputc('\n', out);
  return 0;
}

int ptz_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc < 1) {
    std::fputs(kCameraUsage, err);
    return 2;
  }
  double pan = 0;
  double tilt = 0;
  double zoom = 0;
  double seconds = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string_view arg = argv[i];
    double v = 0;
    if (!parse_double(argv[i + 1], v)) {
      std::fprintf(err, "sen3bot camera ptz: %s needs a number\n", argv[i]);
      return 2;
    }
    if (arg == "--pan") pan = v;
    else if (arg == "--tilt") tilt = v;
    else if (arg == "--zoom") zoom = v;
    else if (arg == "--seconds" && v > 0) seconds = v;
    else {
      std::fputs(kCameraUsage, err);
      return 2;
    }
  }
  auto config = parse_onvif_url(argv[0]);
  if (!config) {
    std::fprintf(err, "sen3bot camera ptz: %s\n", config.error().c_str());
    return 2;
  }
  auto client = camera::onvif::OnvifClient::create(*config);
  if (!client) {
    std::fprintf(err, "sen3bot camera ptz: %s\n", client.error().c_str());
    return 1;
  }
  if (auto s = (*client)->connect(); !s) {
    std::fprintf(err, "sen3bot camera ptz: %s\n", s.error().c_str());
    return 1;
  }
  auto profiles = (*client)->profiles();
  if (!profiles) {
    std::fprintf(err, "sen3bot camera ptz: %s\n", profiles.error().c_str());
    return 1;
  }
  const camera::onvif::Profile* profile = nullptr;
  for (const auto& p : *profiles) {
    if (p.has_ptz && profile == nullptr) profile = &p;
  }
  if (profile == nullptr) {
    std::fprintf(err, "sen3bot camera ptz: no profile has a PTZ configuration\n");
    return 1;
  }
  const Status moved = (*client)->continuous_move(profile->token, pan, tilt, zoom, seconds);
  if (moved) std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  // Always an explicit Stop: cheap cameras ignore the move's Timeout.
  const Status stopped = (*client)->stop(profile->token);
  json::FileSink sink(out);
  json::Writer w(sink);
  w.begin_object()
      .member("profile", profile->token)
      .key("pan").fixed_or_null(pan, 3)
      .key("tilt").fixed_or_null(tilt, 3)
      .key("zoom").fixed_or_null(zoom, 3)
      .key("seconds").fixed_or_null(seconds, 3)
      .member_bool("moved", static_cast<bool>(moved))
      .member_bool("stopped", static_cast<bool>(stopped))
      .member("auth", camera::onvif::to_string((*client)->auth_mode()))
      .end_object();
  std::fputc('\n', out);
  if (!moved) std::fprintf(err, "sen3bot camera ptz: %s\n", moved.error().c_str());
  return moved && stopped ? 0 : 1;
}

}  // namespace

int camera_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc >= 1 && std::string_view(argv[0]) == "probe") return probe(argc - 1, argv + 1, out, err);
  if (argc >= 1 && std::string_view(argv[0]) == "discover") return discover_command(argc - 1, argv + 1, out, err);
  if (argc >= 1 && std::string_view(argv[0]) == "ptz") return ptz_command(argc - 1, argv + 1, out, err);
  std::fputs(kCameraUsage, err);
  return 2;
}

}  // namespace sen3bot::firmware
