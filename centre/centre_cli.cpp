// sen3bot-centre: the fleet centre's programs on the site's broker (the Sensors Synergy Centre
// and the formation controller). Not installed on the robot.
#include "centre_commands.hpp"

#include "cli_util.hpp"

#ifndef SEN3BOT_VERSION
#define SEN3BOT_VERSION "unknown"
#endif

namespace sen3bot::centre {

namespace {

constexpr const char* kUsage =
    "usage: sen3bot-centre <command> [options]\n"
    "\n"
    "The Sen3Bot fleet's central programs, run on the site's computer.\n"
    "\n"
    "commands:\n"
    "  ssc --broker URL --site SITE.yaml [--username U --password-file F --ca-file F]\n"
    "      [--event-log FILE] [--duration S] [--client-id ID]\n"
    "        The Sensors Synergy Centre on the site's MQTT broker (mqtt:// or mqtts://,\n"
    "        the latter with --ca-file): reads every vehicle's VDA 5050 state and\n"
    "        connection and the robots' people reports; sends the robots their orders\n"
    "        and cancels, and publishes each plant AGV's advisory (CLEAR, SLOW, STOP) on\n"
    "        sen3bot/v1/advisory/MANUFACTURER/SERIAL (and, where the site's\n"
    "        agv_cc.direct_pause allows, startPause/stopPause to the AGV). Steps every\n"
    "        0.1 s in real time until SIGINT or SIGTERM or --duration S (0: until a\n"
    "        signal). The password is the first line of --password-file. --event-log\n"
    "        appends each decision with its reason as a JSON line; at the end one JSON\n"
    "        line of counters goes to standard output. --client-id: default ssc. A\n"
    "        restarted centre learns the robots and AGVs again from the retained\n"
    "        connection messages and their next states.\n"
    "  formation --broker URL --example 1|2|3 --team SERIAL,SERIAL,... [--username U\n"
    "      --password-file F --ca-file F] [--client-id ID] [--manufacturer M]\n"
    "      [--interface NAME] [--v-max M_S] [--w-max RAD_S] [--period S] [--hold S]\n"
    "      [--pose-timeout S] [--log FILE.csv] [--duration S]\n"
    "        The centre's formation controller on the site's MQTT broker\n"
    "        (docs/formation.md): the thesis' example 1 (four robots to targets), 2\n"
    "        (three patrol an ellipse) or 3 (a leader and two followers), scaled for\n"
    "        Pioneers, driving the robots named by --team in that order. Reads their\n"
    "        VDA 5050 visualization, steps every --period (0.1 s) and sends each robot\n"
    "        its velocity on sen3bot/v1/formation/MANUFACTURER/SERIAL with --hold (0.5 s,\n"
    "        at most 2): a robot stops by itself when the centre goes quiet. A missing\n"
    "        or stale pose (--pose-timeout, 0.5 s) stops the whole team. --v-max and\n"
    "        --w-max: the robots' limits (0.5 m/s, 1.5 rad/s); each drives at most half.\n"
    "        --log writes one CSV line per step. On SIGINT, SIGTERM or --duration the\n"
    "        team is told to stop and one JSON line of counters goes to standard output.\n"
    "  version\n"
    "        Print the version.\n"
    "  --help, -h\n"
    "        Print this text.\n"
    "\n"
    "exit status: 0 success, 1 run-time failure, 2 bad command line or site file.\n";

}  // namespace

int centre_cli_main(int argc, char** argv, std::FILE* out, std::FILE* err) {
  static constexpr firmware::Command kCommands[] = {
      {"ssc", "", ssc_command},
#ifdef SEN3BOT_HAS_FORMATION
      {"formation", "", formation_command},
#endif
  };
  return firmware::dispatch(argc, argv, "sen3bot-centre", SEN3BOT_VERSION, kUsage, kCommands, out, err);
}

}  // namespace sen3bot::centre
