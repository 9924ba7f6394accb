// A module's entry point: built once per module with SEN3BOT_ROW_<NAME> defined
// (row_module.hpp).
#include "commands.hpp"
#include "row_module.hpp"

using namespace sen3bot;
using namespace sen3bot::firmware;

namespace {

RowModule make() {
  RowModule m;
  m.version = SEN3BOT_VERSION;
#if defined(SEN3BOT_ROW_CAMERA)
  m.camera = [](const camera::CameraConfig& config, hal::Board& board, tasks::Bus& bus, camera::Camera** camera_out) -> std::unique_ptr<tasks::Task> {
    return std::make_unique<CameraTask>(config, board, bus, camera_out);
  };
  m.command = camera_command;
#elif defined(SEN3BOT_ROW_VISION)
  m.vision = [](const VisionTaskConfig& config, const FrameSource& frames,
                tasks::Topic<msg::PersonDetections>& topic) -> std::unique_ptr<tasks::Task> {
    return std::make_unique<VisionTask>(config, frames, topic);
  };
  m.command = detect_command;
#elif defined(SEN3BOT_ROW_QR)
  m.qr = [](const QrTaskConfig& config, const FrameSource& frames, const QrTopics& topics) -> std::unique_ptr<tasks::Task> {
    return std::make_unique<QrTask>(config, frames, topics);
  };
  m.command = cobot_command;
#elif defined(SEN3BOT_ROW_RECOGNITION)
  m.recognition = [](const RecognitionTaskConfig& config, const RecognitionTopics& topics) -> std::unique_ptr<tasks::Task> {
    return std::make_unique<RecognitionTask>(config, topics);
  };
  m.command = recognize_command;
#elif defined(SEN3BOT_ROW_SGP)
  m.command = sgp_command;  // a command alone: its figure is drawn with OpenCV
#else
#error "define the module's row: SEN3BOT_ROW_CAMERA, _VISION, _QR, _RECOGNITION or _SGP"
#endif
  return m;
}

}  // namespace

extern "C" [[gnu::visibility("default")]] const RowModule* sen3bot_row_module() {
  static const RowModule module = make();
  return &module;
}
