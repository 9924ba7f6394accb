// `sen3bot cobot tags`: the printable QR tags of an operator's leg band (docs/cobot/tags.md).
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "commands.hpp"
#include "sen3bot/cobot/qr_reader.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kCobotUsage =
    "usage: sen3bot cobot tags --operator ID --out DIR [--module-px N]\n"
    "  Writes DIR/operator-ID-front.png and DIR/operator-ID-back.png (ID 1..999999). At\n"
    "  300 dpi the default --module-px 47 prints the code 10 cm wide.\n";

int tags_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::uint32_t operator_id = 0;
  bool have_operator = false;
  std::string dir;
  std::uint32_t module_px = cobot::kPrintModulePx;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--operator" && has_value) {
      if (!parse_u32(argv[++i], operator_id) || operator_id == 0 || operator_id > cobot::kMaxOperatorId) {
        std::fprintf(err, "sen3bot cobot tags: --operator: expected 1..%u, got '%s'\n", cobot::kMaxOperatorId, argv[i]);
        return 2;
      }
      have_operator = true;
    } else if (arg == "--out" && has_value) {
      dir = argv[++i];
    } else if (arg == "--module-px" && has_value) {
      if (!parse_u32(argv[++i], module_px) || module_px < 2 || module_px > 200) {
        std::fprintf(err, "sen3bot cobot tags: --module-px: expected 2..200, got '%s'\n", argv[i]);
        return 2;
      }
    } else {
      std::fprintf(err, "sen3bot cobot tags: unknown or incomplete option '%s'\n%s", argv[i], kCobotUsage);
      return 2;
    }
  }
  if (!have_operator || dir.empty()) {
    std::fprintf(err, "sen3bot cobot tags: --operator and --out are required\n%s", kCobotUsage);
    return 2;
  }
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) {
    std::fprintf(err, "sen3bot cobot tags: cannot create %s: %s\n", dir.c_str(), std::strerror(errno));
    return 1;
  }
  for (const msg::TagSide side : {msg::TagSide::front, msg::TagSide::back}) {
    const cobot::Tag tag{operator_id, side};
    const std::string path = dir + "/operator-" + std::to_string(operator_id) +
                             (side == msg::TagSide::front ? "-front.png" : "-back.png");
    if (Status s = cobot::write_tag_png(tag, path, static_cast<int>(module_px)); !s) {
      std::fprintf(err, "sen3bot cobot tags: %s\n", s.error().c_str());
      return 1;
    }
    Result<cobot::TagPayload> payload = cobot::encode_tag(tag);
    // At 300 dpi: the code's width in cm from its modules.
    const double code_cm = cobot::kTagQrModules * static_cast<double>(module_px) / 300.0 * 2.54;
    std::fprintf(out, "wrote %s: operator %u %s, payload %s, code %.1f cm wide at 300 dpi\n", path.c_str(),
                 operator_id, cobot::side_name(side), payload ? payload->c_str() : "?", code_cm);
  }
  return 0;
}

}  // namespace

int cobot_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc >= 1 && std::string_view(argv[0]) == "tags") return tags_command(argc - 1, argv + 1, out, err);
  std::fputs(kCobotUsage, err);
  return 2;
}

}  // namespace sen3bot::firmware
