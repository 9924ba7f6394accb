#include "cli.hpp"

#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "commands.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "runner.hpp"
#include "sen3bot/capture/dump.hpp"

#ifndef SEN3BOT_VERSION
#define SEN3BOT_VERSION "unknown"
#endif

namespace sen3bot::firmware {

namespace {

constexpr const char* kUsage =
    "usage: sen3bot <command> [options]\n"
    "\n"
    "Real-time controller firmware for the Sen3Bot mobile robot (Pioneer 3-DX base,\n"
    "SICK LMS200 laser, ONVIF/RTSP camera).\n"
    "\n"
    "commands:\n"
    "  run --config FILE [--duration S]\n"
    "        Load the configuration, build the task table and run it on the robot's\n"
    "        devices in real time until SIGINT or SIGTERM, the configured duration or\n"
    "        the end of the mission, then print the mission report (with a navigation\n"
    "        section) and task statistics. --duration overrides run.duration_s (0:\n"
    "        until a signal). A configuration with a simulated robot runs with\n"
    "        sen3bot-sim.\n"
    "  graph --config FILE [--mermaid]\n"
    "        The data flow the configuration wires, without starting anything: each\n"
    "        thread's rows with the devices they talk to and the topics they read and\n"
    "        write, then each topic's writer and readers, then the rows left out and\n"
    "        why. --mermaid prints it as a Mermaid flowchart instead (a figure where\n"
    "        Markdown is rendered). docs/architecture.md quotes this for the robot's\n"
    "        configuration.\n"
    "  map --carmen FILE --out DIR/NAME.yaml [--resolution R] [--poses FILE]\n"
    "        A map built from a recorded drive (laser SLAM: submaps, loop closures, a pose\n"
    "        graph), written as map_server YAML + PGM; --poses writes each scan's solved\n"
    "        pose (index x y theta); a JSON summary on stdout.\n"
    "  plan --map MAP.yaml --start X,Y --goal X,Y [--waypoints FILE] [--unit-cost]\n"
    "        One global plan (A* with waypoint attraction) on the map's costmap, as\n"
    "        JSON: length_m, cells, expansions, time_ms, path [[x, y], ...] in metres.\n"
    "        --unit-cost plans on the bare occupancy grid (no inflation, no footprint).\n"
    "  sgp --map MAP.yaml --curve CURVE.yaml --start X,Y --goal X,Y [--direction 1|-1]\n"
    "      [--png FILE]\n"
    "        The supervisory planner's safe path: the map's obstacle ellipses, the safe\n"
    "        curve checked against them, the field integrated from the start to where\n"
    "        the curve passes closest to the goal. JSON: stop, waypoints [[x, y], ...],\n"
    "        length_m, iterations, time_ms, min_barrier, ellipses. --png draws the map,\n"
    "        ellipses, curve, field and waypoints. Exit status 1 when the path stops\n"
    "        short of that place (the reason in stop).\n"
    "  fuse --capture SCANS.s3bcap --boxes BOXES.jsonl [--map MAP.yaml]\n"
    "       [--pose X,Y,THETA_DEG] [--window S] [--offset S]\n"
    "        The camera-laser fusion offline: each frame of the box file (the\n"
    "        detector replay's JSON lines) fused with the capture's LMS200 scan\n"
    "        nearest in time (--offset moves the boxes onto the capture's clock),\n"
    "        from the laser pose given (default 0,0,0: the laser's own frame), the\n"
    "        map's obstacles left out as background. JSON lines: the people placed\n"
    "        and each box's verdict.\n"
    "  detect --image FILE [--scale S] [--threshold T] [--repeat N] [--png FILE]\n"
    "        The on-board people detector (OpenCV's HOG people coefficients) on an\n"
    "        image, the frame shrunk by --scale (0.5) first: JSON with the boxes in\n"
    "        the image's pixels and their confidence, and the median time of --repeat\n"
    "        runs. --png draws the boxes. (Where OpenCV's objdetect is built in.)\n"
    "  capture dump FILE\n"
    "        Print a wire capture (.s3bcap) as a timestamped hex listing.\n"
    "  decode p2os CAPTURE\n"
    "        Decode the Pioneer base packets of a wire capture as JSON lines (time,\n"
    "        direction, type, fields).\n"
    "  drive --port DEV|tcp://HOST:PORT --vel M_S --rvel RAD_S --seconds S [--baud B]\n"
    "        Connect to the base, enable the motors, drive at the given velocities, print\n"
    "        odometry as JSON lines, then stop, disable and close.\n"
    "  decode lms200 CAPTURE\n"
    "        Decode the SICK LMS200 telegrams of a wire capture as JSON lines (time,\n"
    "        direction, code, decoded fields; scans with ranges_m, null where invalid).\n"
    "  scan --port DEV --baud B --variant 180/0.5 --units cm|mm --count N [--timeout S]\n"
    "        Connect to an LMS200 (probing its baud rate), print N scans as JSON lines\n"
    "        (t_s, angle_min_rad, angle_increment_rad, ranges_m, units, baud), then stop.\n"
    "  camera discover [--timeout S]\n"
    "        WS-Discovery probe for ONVIF cameras; prints them as a JSON array.\n"
    "  camera ptz onvif://user:pass@host[:port] --pan P --tilt T --zoom Z --seconds S\n"
    "        ONVIF ContinuousMove (velocities in [-1, 1]) for S seconds, then Stop.\n"
    "  camera probe URL [--transport tcp|udp] [--frames N] [--save DIR] [--timeout S]\n"
    "        Connect to a camera (rtsp://[user:pass@]host[:port]/path, or\n"
    "        onvif://user:pass@host[:port] to ask ONVIF for the stream URI), decode N\n"
    "        frames (default 30) and end with one JSON line: codec, width, height,\n"
    "        transport, frames_decoded, frames_dropped, fps, latency_ms_p50. --save\n"
    "        writes each frame seen as PNG. Stops at once when the camera cannot\n"
    "        work (unsupported codec, no video, credentials rejected, no such stream).\n"
    "        Exit status 1 when no frame was decoded or the camera cannot work.\n"
    "  can dump SOURCE [--node N] [--count N]\n"
    "        Decode CAN frames as CANopen, one JSON object a frame (t_s, interface, id,\n"
    "        kind, node and the decoded fields; error frames as link events). SOURCE\n"
    "        is a candump -l log, - for standard input, or else a SocketCAN interface,\n"
    "        printed live until SIGINT or --count frames. --node keeps one node's\n"
    "        frames, NMT commands to it or to all, and error frames. A bad log line\n"
    "        prints {\"line\":N,\"error\":...} and the dump goes on; exit status 1.\n"
    "  can io --iface IFACE --node N [--set OUT=0|1 ...] [--timeout S]\n"
    "        Bring a CiA 401 I/O node up with the master (configuration over SDO,\n"
    "        NMT start, heartbeat), set outputs 1..8 (the others off), wait until\n"
    "        they went out and print one JSON object: state, inputs, outputs,\n"
    "        heartbeat state, event counters, the last emergency. Exit status 1 when\n"
    "        the node is not up within --timeout (3 s), with the master's state and\n"
    "        counters. Against an emulated node: sen3bot-sim can io --iface sim.\n"
    "  recognize --paths FILE [--progressive] [--model M] [--operations O]\n"
    "        The operation recognizer on recorded worker paths (one JSON object per\n"
    "        line: name, operation (the truth, optional), points [[x, y], ...]): per\n"
    "        path the probability of each operation of O (config/cobot/operations.yaml)\n"
    "        by the model M (config/cobot/operations-model.yaml.gz); --progressive adds\n"
    "        the most probable operation and the right one's probability at every 10 %\n"
    "        of the path. A bad line is an error naming it. (Where OpenCV's ml module is\n"
    "        built in.)\n"
    "  cobot tags --operator ID --out DIR [--module-px N]\n"
    "        Write an operator's leg band tags, DIR/operator-ID-front.png and -back.png\n"
    "        (ID 1..999999): each QR code with its quiet zone and a caption. At 300 dpi\n"
    "        the default --module-px 47 prints the code 10 cm wide. (Where OpenCV's\n"
    "        objdetect is built in.)\n"
    "  version\n"
    "        Print the firmware version.\n"
    "  --help, -h\n"
    "        Print this text.\n"
    "\n"
    "exit status: 0 success, 1 run-time failure, 2 bad command line or configuration,\n"
    "3 the mission failed (a goal not reached).\n";

int run_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  const StopSignalsBlocked blocked;
  RunOptions options;
  if (int rc = parse_run_options(argc, argv, "sen3bot", options, err); rc != 0) return rc;
  Result<FirmwareConfig> loaded = load_config(options.config_path);
  if (!loaded) {
    std::fprintf(err, "sen3bot: %s\n", loaded.error().c_str());
    return 2;
  }
  FirmwareConfig& config = *loaded;
  apply(options, config);
  if (config.clock != ClockMode::realtime) {
    std::fprintf(err, "sen3bot: %s: run.clock: the robot runs in real time; lockstep time needs a simulated "
                      "robot (sen3bot-sim run)\n", config.source_path.c_str());
    return 2;
  }
  hal::PosixBoard board(hal::PosixBoard::Lines{config.board.estop_input, config.board.light_output});
  if (Status s = board.open_lines(); !s) {
    std::fprintf(err, "sen3bot: %s: %s\n", config.source_path.c_str(), s.error().c_str());
    return 1;
  }
  Firmware fw(config, board, out);
  return run_firmware(fw, board, config, out, err);
}

int graph_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string config_path;
  bool mermaid = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--config" && i + 1 < argc) {
      config_path = argv[++i];
    } else if (arg == "--mermaid") {
      mermaid = true;
    } else {
      std::fprintf(err, "sen3bot graph: unknown argument '%s'\nusage: sen3bot graph --config FILE [--mermaid]\n",
                   argv[i]);
      return 2;
    }
  }
  if (config_path.empty()) {
    std::fprintf(err, "usage: sen3bot graph --config FILE [--mermaid]\n");
    return 2;
  }
  // A simulated robot's configuration names sections of the simulator's board: accepted here,
  // as the wiring does not depend on them.
  static constexpr std::string_view kBoardSections[] = {"sim"};
  Result<FirmwareConfig> loaded = load_config(config_path, kBoardSections);
  if (!loaded) {
    std::fprintf(err, "sen3bot graph: %s\n", loaded.error().c_str());
    return 2;
  }
  hal::PosixBoard board(hal::PosixBoard::Lines{});  // no line opened: nothing starts
  Firmware fw(*loaded, board, out);
  if (Status s = fw.wire(); !s) {
    std::fprintf(err, "sen3bot graph: %s\n", s.error().c_str());
    return 2;
  }
  if (mermaid) {
    print_graph_mermaid(fw.wiring(), out);
  } else {
    std::fprintf(out, "sen3bot data flow: %s\n\n", config_path.c_str());
    print_graph(fw.wiring(), out);
  }
  return 0;
}

int capture_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc == 2 && std::string_view(argv[0]) == "dump") {
    if (Status s = capture::dump(argv[1], out); !s) {
      std::fprintf(err, "sen3bot capture dump: %s\n", s.error().c_str());
      return 1;
    }
    return 0;
  }
  std::fprintf(err, "usage: sen3bot capture dump FILE\n");
  return 2;
}

// The commands whose libraries are heavy run from their module (row_module.hpp).
int sgp_from_module(int argc, char** argv, std::FILE* out, std::FILE* err) {
  return row_module_command("sgp", "sen3bot sgp", argc, argv, out, err);
}
int camera_from_module(int argc, char** argv, std::FILE* out, std::FILE* err) {
  return row_module_command("camera", "sen3bot camera", argc, argv, out, err);
}
[[maybe_unused]] int detect_from_module(int argc, char** argv, std::FILE* out, std::FILE* err) {
  return row_module_command("vision", "sen3bot detect", argc, argv, out, err);
}
[[maybe_unused]] int recognize_from_module(int argc, char** argv, std::FILE* out, std::FILE* err) {
  return row_module_command("recognition", "sen3bot recognize", argc, argv, out, err);
}
[[maybe_unused]] int cobot_from_module(int argc, char** argv, std::FILE* out, std::FILE* err) {
  return row_module_command("qr", "sen3bot cobot", argc, argv, out, err);
}

}  // namespace

int cli_main(int argc, char** argv, std::FILE* out, std::FILE* err) {
  static constexpr Command kCommands[] = {
      {"run", "", run_command},
      {"graph", "", graph_command},
      {"plan", "", plan_command},
      {"map", "", map_command},
      {"sgp", "", sgp_from_module},
      {"fuse", "", fuse_command},
#ifdef SEN3BOT_HAS_HOG
      {"detect", "", detect_from_module},
#endif
      {"capture", "", capture_command},
      {"decode", "p2os", decode_p2os_command},
      {"decode", "lms200", decode_lms200_command},
      {"drive", "", drive_command},
      {"scan", "", scan_command},
      {"camera", "", camera_from_module},
      {"can", "dump", can_dump_command},
      {"can", "io", can_io_command},
#ifdef SEN3BOT_HAS_RECOGNIZER
      {"recognize", "", recognize_from_module},
#endif
#ifdef SEN3BOT_HAS_COBOT_TAGS
      {"cobot", "", cobot_from_module},
#endif
  };
  return dispatch(argc, argv, "sen3bot", SEN3BOT_VERSION, kUsage, kCommands, out, err);
}

}  // namespace sen3bot::firmware
