#pragma once
// The rows whose libraries are heavy are shared modules, loaded only when the configuration
// uses them (docs/firmware.md, "Row modules"):
//   sen3bot-camera.so       the camera row and `sen3bot camera` (libavcodec, libcurl)
//   sen3bot-vision.so       the on-board people detector and `sen3bot detect` (OpenCV objdetect)
//   sen3bot-qr.so           the QR tag reader and `sen3bot cobot tags` (OpenCV objdetect)
//   sen3bot-recognition.so  operation recognition and `sen3bot recognize` (OpenCV ml)
//   sen3bot-sgp.so          `sen3bot sgp`, whose --png figure is drawn with OpenCV (no row)
// The robot binary itself links none of those libraries. Each module exports one C function,
// sen3bot_row_module(), returning its RowModule. Modules are looked for in $SEN3BOT_MODULE_DIR,
// next to the running binary, in ../lib/sen3bot from it, and in the build's firmware folder.
#include <cstdint>
#include <cstdio>
#include <memory>

#include "camera_task.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/tasks/task.hpp"
#include "qr_task.hpp"
#include "recognition_task.hpp"
#include "vision_task.hpp"

namespace sen3bot::firmware {

// Bumped when RowModule or a row's constructor arguments change.
inline constexpr std::uint32_t kRowModuleAbi = 2;

struct RowModule {
  std::uint32_t abi = kRowModuleAbi;
  // The rows' sizes as the module was built: a module from another build is refused.
  std::uint32_t camera_size = sizeof(CameraTask);
  std::uint32_t vision_size = sizeof(VisionTask);
  std::uint32_t qr_size = sizeof(QrTask);
  std::uint32_t recognition_size = sizeof(RecognitionTask);
  const char* version = nullptr;
  // A module sets its own row's factory and its command; the others stay null.
  // Each row is owned through its tasks::Task base, so that its destructor is the module's. The
  // firmware never calls or downcasts a row's own class: only the module has its type_info
  // (with -fsanitize=vptr each such call needs it); what it shares goes through plain slots.
  std::unique_ptr<tasks::Task> (*camera)(const camera::CameraConfig&, hal::Board&, tasks::Bus&,
                                         camera::Camera** camera_out) = nullptr;
  std::unique_ptr<tasks::Task> (*vision)(const VisionTaskConfig&, const FrameSource&,
                                         tasks::Topic<msg::PersonDetections>&) = nullptr;
  std::unique_ptr<tasks::Task> (*qr)(const QrTaskConfig&, const FrameSource&, const QrTopics&) = nullptr;
  std::unique_ptr<tasks::Task> (*recognition)(const RecognitionTaskConfig&, const RecognitionTopics&) = nullptr;
  int (*command)(int argc, char** argv, std::FILE* out, std::FILE* err) = nullptr;
};

// Loads sen3bot-<name>.so once and keeps it for the life of the process (its rows' code lives
// there). Errc::not_found names the file and the folders searched.
Result<const RowModule*> load_row_module(const char* name);

// Runs a module's command (`sen3bot camera ...`), or says why the module cannot be loaded (2).
int row_module_command(const char* module, const char* program, int argc, char** argv, std::FILE* out,
                       std::FILE* err);

}  // namespace sen3bot::firmware
