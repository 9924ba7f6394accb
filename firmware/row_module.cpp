#include "row_module.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {
namespace {

std::vector<std::string> module_dirs() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("SEN3BOT_MODULE_DIR"); env != nullptr && *env != '\0') dirs.emplace_back(env);
  char exe[4096];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  const std::string path = n > 0 ? std::string(exe, static_cast<std::size_t>(n)) : std::string();
  if (const std::size_t slash = path.find_last_of('/'); slash != std::string::npos) {
    const std::string dir = path.substr(0, slash);
    dirs.push_back(dir);
    dirs.push_back(dir + "/../lib/sen3bot");
  }
#ifdef SEN3BOT_MODULE_BUILD_DIR
  dirs.emplace_back(SEN3BOT_MODULE_BUILD_DIR);
#endif
  return dirs;
}

Result<const RowModule*> open_module(const std::string& file) {
  std::string searched;
  for (const std::string& dir : module_dirs()) {
    const std::string path = dir + "/" + file;
    if (::access(path.c_str(), F_OK) != 0) {
      searched += searched.empty() ? dir : ", " + dir;
      continue;
    }
    void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) return Error::format(Errc::io, "%s", ::dlerror());
    using Entry = const RowModule* (*)();
    auto entry = reinterpret_cast<Entry>(::dlsym(handle, "sen3bot_row_module"));
    const RowModule* module = entry != nullptr ? entry() : nullptr;
    const RowModule expected;
    if (module == nullptr || module->abi != expected.abi || module->camera_size != expected.camera_size ||
        module->vision_size != expected.vision_size || module->qr_size != expected.qr_size ||
        module->recognition_size != expected.recognition_size || module->version == nullptr ||
        std::strcmp(module->version, SEN3BOT_VERSION) != 0) {
      ::dlclose(handle);
      return Error::format(Errc::not_supported, "%s: built for another version of the firmware; rebuild it", path.c_str());
    }
    return module;  // never closed: the rows it built run its code
  }
  return Error::format(Errc::not_found, "%s not found (looked in %s); build it with the firmware or install it next to the binary",
                       file.c_str(), searched.c_str());
}

}  // namespace

Result<const RowModule*> load_row_module(const char* name) {
  static std::mutex mutex;
  static std::map<std::string, const RowModule*> loaded;
  const std::lock_guard<std::mutex> lock(mutex);
  const std::string file = std::string("sen3bot-") + name + ".so";
  if (auto it = loaded.find(file); it != loaded.end()) return it->second;
  Result<const RowModule*> module = open_module(file);
  if (module) loaded.emplace(file, *module);
  return module;
}

int row_module_command(const char* module, const char* program, int argc, char** argv, std::FILE* out,
                       std::FILE* err) {
  Result<const RowModule*> loaded = load_row_module(module);
  if (!loaded) {
    std::fprintf(err, "%s: %s\n", program, loaded.error().c_str());
    return 2;
  }
  return (*loaded)->command(argc, argv, out, err);
}

// --- The rows in modules (task_table.hpp) ----------------------------------------------------

namespace {

// Where the vision and QR rows take their frames: a simulated camera's pool, or the camera row's.
FrameSource frame_source(Wiring& w) {
  if (w.shared.external_frames != nullptr) {
    w.takes("frames of a simulated camera");
    return FrameSource{w.shared.external_frames};
  }
  if (w.uses("camera") == nullptr) return FrameSource{};
  return FrameSource{nullptr, &w.shared.camera};
}

}  // namespace

Status make_camera(Wiring& w) {
  if (!w.config.devices.has_camera) return w.absent("needs devices.camera");
  Result<const RowModule*> module = load_row_module("camera");
  if (!module) return Error::format(module.error().code(), "%s: devices.camera: %s", w.file(), module.error().c_str());
  // The URL without its credentials (user:password@ before the host).
  std::string url = w.config.devices.camera.rtsp.url;
  if (const std::size_t scheme = url.find("://"); scheme != std::string::npos) {
    const std::size_t host = scheme + 3;
    const std::size_t at = url.rfind('@', url.find('/', host));
    if (at != std::string::npos && at >= host) url.erase(host, at + 1 - host);
  }
  w.takes("RTSP/RTP from " + url + ": H.264/MJPEG decoded into the frame pool");
  w.sends("RTSP requests (OPTIONS, DESCRIBE, SETUP, PLAY, keep-alive), RTCP receiver reports");
  w.adopt((*module)->camera(w.config.devices.camera, w.board, w.bus, &w.shared.camera));
  return Status::success();
}

Status make_vision(Wiring& w) {
  const NavigationSection& n = w.config.navigation;
  if (!n.enabled || !n.people_enabled || n.people_detector != "onboard" || w.shared.external_people != nullptr)
    return w.absent("needs navigation.people.detector: onboard");
#ifdef SEN3BOT_HAS_HOG
  if (!w.config.devices.has_camera && w.shared.external_frames == nullptr)
    return Error::format(Errc::config, "%s: navigation.people.detector: onboard needs devices.camera", w.file());
  const nav::CameraCalibration camera;
  VisionTaskConfig vision;
  vision.hog = n.onboard_hog;
  vision.rate_hz = n.onboard_rate_hz;
  vision.calibration_width_px = static_cast<std::uint32_t>(camera.width_px);
  vision.calibration_height_px = static_cast<std::uint32_t>(camera.height_px);
  Result<const RowModule*> module = load_row_module("vision");
  if (!module)
    return Error::format(module.error().code(), "%s: navigation.people.detector: onboard: %s", w.file(),
                         module.error().c_str());
  w.adopt((*module)->vision(vision, frame_source(w), w.writes(&Topics::detections)));
  return Status::success();
#else
  return Error::format(Errc::config,
                       "%s: navigation.people.detector: onboard: this build has no on-board detector (it needs "
                       "OpenCV's objdetect module, libopencv-objdetect-dev)",
                       w.file());
#endif
}

Status make_qr(Wiring& w) {
  const CobotSection& k = w.config.cobot;
  if (!k.enabled || !w.config.navigation.enabled) return w.absent("needs a cobot section and a camera");
  if (w.shared.external_frames == nullptr && !w.config.devices.has_camera)
    return w.absent("needs a cobot section and a camera");
#ifdef SEN3BOT_HAS_QR
  QrTaskConfig qr;
  qr.rate_hz = k.qr_rate_hz;
  qr.reach_m = k.qr_reach_m;
  qr.band_height_m = k.task.band_height_m;
  qr.laser_height_m = k.task.laser_height_m;
  qr.tag_side_m = k.tag_side_m;
  qr.whole_frame = k.qr_whole_frame;
  qr.camera = nav::CameraCalibration{};
  qr.laser_mount = w.shared.laser_mount;
  Result<const RowModule*> module = load_row_module("qr");
  if (!module)
    return Error::format(module.error().code(), "%s: cobot: the QR tag reader: %s", w.file(), module.error().c_str());
  const FrameSource frames = frame_source(w);
  w.adopt((*module)
              ->qr(qr, frames, QrTopics{w.reads(&Topics::people), w.reads(&Topics::pose), w.writes(&Topics::tags)}));
  return Status::success();
#else
  return Error::format(Errc::config,
                       "%s: cobot: this build has no QR tag reader (it needs OpenCV's objdetect module, "
                       "libopencv-objdetect-dev)",
                       w.file());
#endif
}

Status make_recognition(Wiring& w) {
  const CobotSection& k = w.config.cobot;
  if (!k.enabled || !k.recognition || !w.config.navigation.enabled) return w.absent("needs cobot.recognition");
#ifdef SEN3BOT_HAS_RECOGNITION
  RecognitionTaskConfig recognition;
  recognition.operations_path = k.operations_path;
  recognition.model_path = k.model_path;
  recognition.rate_hz = k.recognition_rate_hz;
  Result<const RowModule*> module = load_row_module("recognition");
  if (!module) return Error::format(module.error().code(), "%s: cobot.recognition: %s", w.file(), module.error().c_str());
  w.adopt((*module)
              ->recognition(recognition,
                            RecognitionTopics{w.reads(&Topics::worker_path), w.writes(&Topics::operation),
                                              w.writes(&Topics::operation_reference)}));
  return Status::success();
#else
  return Error::format(Errc::config,
                       "%s: cobot.recognition: this build has no operation recognizer (it needs OpenCV's ml module, "
                       "libopencv-ml-dev)",
                       w.file());
#endif
}

}  // namespace sen3bot::firmware
