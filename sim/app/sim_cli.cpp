#include <cstdio>
#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "runner.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sim_commands.hpp"

#ifndef SEN3BOT_VERSION
#define SEN3BOT_VERSION "unknown"
#endif

namespace sen3bot::sim {

namespace {

constexpr const char* kUsage =
    "usage: sen3bot-sim <command> [options]\n"
    "\n"
    "The Sen3Bot firmware on a simulated robot: the same task table and drivers as the\n"
    "robot's sen3bot, over a simulated board whose devices are wire-exact emulators\n"
    "driven by a ground-truth world; and the emulators on their own for other clients.\n"
    "\n"
    "commands:\n"
    "  run --config FILE [--duration S] [--clock lockstep|realtime]\n"
    "        Load the configuration (its `sim` section is the simulated robot), run the\n"
    "        firmware until SIGINT or SIGTERM, the configured duration or the end of the\n"
    "        mission, then print the mission report, what the ground truth says and the\n"
    "        task statistics. --duration overrides run.duration_s (0: until a signal);\n"
    "        --clock overrides run.clock: 'lockstep' runs simulated time as fast as the\n"
    "        CPU allows over in-memory links, 'realtime' runs on the monotonic clock\n"
    "        with one thread per task group, the drivers on real ptys.\n"
    "  sim --scenario NAME [--config FILE] [--realtime] [--seed N] [--report DIR]\n"
    "        Run a named scenario (sen3bot-sim sim --list shows them), each case a whole\n"
    "        firmware run from config/sim.yaml; with --report write DIR/report.json and\n"
    "        a PNG per case (result line, map in metres, safe path, plan, true and\n"
    "        estimated paths, footprints, people, contacts). Exit status 3 when a case\n"
    "        misses its goal or collides.\n"
    "  sim --scenario cobot [--attempts N] [--case NAME] [--config FILE] [--seed N] [--report DIR]\n"
    "        The collaborative mode (docs/cobot.md): operators ask a waiting robot to follow\n"
    "        them and back, N times per case, and fail to in each way it must refuse; the\n"
    "        report gives per case the toggles, false toggles, refusals by reason and the\n"
    "        follow distances. Exit status 3 when a case fails.\n"
    "  sim --list\n"
    "        List the scenarios and their cases.\n"
    "  fleet-sim --scenario net-1|net-2|net-3 [--realtime] [--report DIR] [--site FILE]\n"
    "      [--config FILE]\n"
    "        The fleet's scenarios in lockstep: several robots (each a whole firmware), plant\n"
    "        AGVs speaking VDA 5050 and the Sensors Synergy Centre on one in-process broker;\n"
    "        with --report write DIR/report.json (timeline, AGV speeds, closest AGV-person\n"
    "        distance, the advice's lead on the AGV's own scanner), DIR/events.jsonl and\n"
    "        PNGs of the site. Exit status 3 when a scenario's checks fail. --list lists them.\n"
    "        --realtime: the same scenario in real time as separate programs on a Mosquitto\n"
    "        it starts on a free loopback port (one `sen3bot-sim run` per robot, `sen3bot\n"
    "        ssc`, one `sen3bot-sim agv` per AGV, found beside this binary); the plant's\n"
    "        master control and an observer run here. The report (no PNGs) comes from the\n"
    "        centre's event log and the AGVs' states and advisories, with \"mode\":\n"
    "        \"realtime\"; the programs' logs go to DIR.\n"
#ifdef SEN3BOT_HAS_FORMATION
    "  formation --example 1|2|3 [--report DIR] [--runs N] [--seed S] [--duration S]\n"
    "      [--config FILE]\n"
    "        Formation and patrolling of several robots with the centre's vector-field\n"
    "        controller (docs/formation/examples.md): 1 four robots to targets, 2 three\n"
    "        patrolling an ellipse, 3 a leader on a circle and two followers; each robot a\n"
    "        whole firmware (config/sim.yaml in config/maps/formation.yaml), the centre's\n"
    "        formation service on the same in-process broker, lockstep. Run 0 starts from\n"
    "        the example's poses, runs 1..N-1 from seeded perturbations (+-0.15 m, +-0.3\n"
    "        rad). --report writes DIR/formation.json (per run and over the runs: closest\n"
    "        robots, wall contacts, targets, formation error, convergence), trajectories.png,\n"
    "        distances.png and distances.csv. Exit status 0 when every run meets the bounds.\n"
#endif
    "  agv --broker URL --serial S [--manufacturer M] [--map-id ID] [--speed M_S]\n"
    "      [--x X --y Y --theta RAD] [--duration S] [--username U --password-file F\n"
    "      --ca-file F] [--client-id ID]\n"
    "        One simulated plant AGV in real time (20 Hz) on a real MQTT broker: a VDA 5050\n"
    "        vehicle (default manufacturer PlantAGV, map map, 1 m/s, from 0,0,0) that\n"
    "        takes orders and instant actions (startPause, stopPause, cancelOrder) from\n"
    "        master control, reports its state with the nodes ahead, and obeys its\n"
    "        advisory where the broker lets it read it. No people are simulated. Until\n"
    "        SIGINT or SIGTERM or --duration S; then OFFLINE and one JSON line with\n"
    "        its pose, pause and advice.\n"
    "  experiment dol --speed M_S --runs N [--boxes K] [--no-dol] [--no-prediction]\n"
    "                 [--no-baseline] [--seed S] [--jobs J] [--report DIR] [--config FILE]\n"
    "        The thesis' moving-obstacle experiment: the robot crosses the empty 10 m x 6 m\n"
    "        arena of config/dol_arena.yaml (default --config) 8 m while K (default 3,\n"
    "        at most 8) 20 cm boxes walk back and forth across it at M_S. Run i uses\n"
    "        seed S+i (default S 1) for the boxes' lanes and phases and the noise. Each\n"
    "        seed runs with the dynamic obstacle layer (DOL) and without it (the\n"
    "        baseline); --no-dol: the baseline only; --no-baseline: DOL only;\n"
    "        --no-prediction: the DOL variant without the planner's mover prediction.\n"
    "        J worker processes (default: the online CPUs). Prints the thesis' table\n"
    "        (smooth navigations, wait recoveries, collisions, successful) and the smooth\n"
    "        runs' travel times; with --report writes DIR/report.json, a box plot\n"
    "        DIR/travel_times.png and DIR/sample_run.png (the first seed's run at its\n"
    "        closest approach to a box). Exit status 0 when the runs completed.\n"
    "  experiment crowd (--scene circle|crossing|corridor|square [--people N]\n"
    "                   [--behaviour social|blind|orca] | --trajectories FILE) --runs N\n"
    "                   [--seed S] [--jobs J] [--variant default|no-people]...\n"
    "                   [--report DIR] [--config FILE]\n"
    "        The crowd-navigation benchmark (docs/crowd.md): run i is the scene drawn\n"
    "        from seed S+i (default S 1; a recording: its busiest place, from a moment\n"
    "        the seed draws, people replayed) with the firmware of config/crowd.yaml\n"
    "        (default --config) driving from the scene's start to its goal within its\n"
    "        time limit. Variants (default: both): default, the configuration as\n"
    "        shipped; no-people, without the person detector, fusion and cages.\n"
    "        J worker processes (default: the online CPUs). Prints success, collision,\n"
    "        contact and timeout rates with 95 % Wilson intervals, time to goal,\n"
    "        time and path ratios, distances to people, zone times, cage entries and\n"
    "        jerk per variant; with --report writes DIR/report.json, DIR/runs.csv,\n"
    "        DIR/time_to_goal.png and the scene's map. Exit status 0 when the runs\n"
    "        completed.\n"
#ifdef SEN3BOT_HAS_RECOGNIZER
    "  experiment operations --runs N [--report DIR] [--seed S] [--model M]\n"
    "                        [--operations O] [--save-paths FILE] [--style NAME]\n"
    "                        [--first-task] [--no-baseline] [--baseline-per-class N]\n"
    "        Operation recognition on simulated workers (docs/cobot/recognition.md): N\n"
    "        walks per operation of config/cobot/operations.yaml (default --operations)\n"
    "        in the held-out walking style (default rushed; --style another), recorded\n"
    "        as the robot records them, classified whole and at every 10 % of the path\n"
    "        by the model M (default config/cobot/operations-model.yaml.gz). Unless\n"
    "        --no-baseline, the same classifier is trained on the occupancy image alone\n"
    "        (the thesis' input) and compared. Prints the progressive table, the\n"
    "        confusion and whether the targets are met; --report writes DIR/report.json,\n"
    "        confusion.png, progressive.png and paths.png; --save-paths the walks as a\n"
    "        paths file for `sen3bot recognize`. --first-task: the robot records from\n"
    "        the worker's first task on, not from when they engage it after that task.\n"
    "        Exit status 0 when it ran.\n"
    "  train operations --out MODEL [--per-class N] [--seed S] [--operations O]\n"
    "                   [--hidden N] [--encoding occupancy|occupancy_order]\n"
    "                   [--references FILE]\n"
    "        Train the operation recognizer on N (default 480) simulated walks per\n"
    "        operation in the four training styles (seed S, default 1), print the\n"
    "        validation accuracy and write MODEL (OpenCV's format, gzip for .gz).\n"
    "        --references FILE writes the robot's reference route per operation as\n"
    "        the operations file's references block (tools/train_operations.sh).\n"
#endif
    "  slam-check --carmen LOG [--poses NAME=FILE ...] [--odometry] [--figure DIR]\n"
    "             [--min-gap N] [--max-distance M]\n"
    "        How far mapping trajectories (`sen3bot map --poses` files, NAME=FILE; the\n"
    "        log's raw odometry with --odometry) agree with themselves where the robot\n"
    "        came back: pairs of scans at least N (default 200) scans apart whose poses\n"
    "        are within M (default 1.0) m and 30 degrees, at most one per 10 scans, each\n"
    "        scan matched against a grid of the other alone from the trajectory's\n"
    "        relative pose (+-0.3 m, +-15 degrees); the disagreement is how far the match\n"
    "        moves. Per trajectory on its own pairs and on the pairs of the first one:\n"
    "        pairs, matched (score 0.5 and over), mean, median and 95th percentile of the\n"
    "        translational and rotational disagreement, as JSON. --figure DIR: a PNG per\n"
    "        trajectory of the map drawn from every scan at its poses, with the trajectory.\n"
    "  can io --iface sim --node N [--set OUT=0|1 ...] [--timeout S] [--sim-inputs 0xHH]\n"
    "         [--sim-silent]\n"
    "        The robot's `sen3bot can io` against an emulated CiA 401 node on an\n"
    "        in-memory bus: --sim-inputs sets its inputs, --sim-silent makes it a node\n"
    "        that never answers. A demonstration and a test of the command.\n"
    "  p2os-emulator (--pty LINK | --tcp PORT) [--name NAME] [--watchdog stop|resume]\n"
    "        Run the Pioneer 3-DX (ARCOS) emulator until SIGINT: on a pseudo-terminal\n"
    "        whose slave is symlinked at LINK, or on a TCP port (MobileSim style).\n"
    "        --watchdog resume: the next packet after a watchdog stop resumes the old\n"
    "        setpoints, as the ARCOS manual says; default stop: only a new motion command.\n"
    "  lms200-emulator --pty LINK [--map MAP.yaml --pose X,Y,TH] [--baud B] [--variant A/R]\n"
    "                  [--units cm|mm] [--mode M] [--indices on|off] [--status S] [--fault F]...\n"
    "        Run the LMS200 emulator until SIGINT on a pseudo-terminal symlinked at LINK;\n"
    "        ranges from a ROS map_server map (default: a built-in 8 m x 6 m room).\n"
    "        --baud: power-on rate 9600 (default), 19200, 38400 or 500000; --variant:\n"
    "        180/1 (default), 180/0.5, 100/1, 100/0.5, 100/0.25; --units: cm (default) or mm;\n"
    "        --mode: measuring mode 0x00 (default) to 0x06, 0x0F, 0x3F; --indices: real-time\n"
    "        indices in scans; --status: status byte (default 0x10); --fault, repeatable:\n"
    "        crc=N, truncate=N, false-header=N, oversize-len=N, invalid-values=N, dazzle=N\n"
    "        (every Nth scan), silent, no-ack, device-fault.\n"
    "  version\n"
    "        Print the version.\n"
    "  --help, -h\n"
    "        Print this text.\n"
    "\n"
    "exit status: 0 success, 1 run-time failure, 2 bad command line or configuration,\n"
    "3 the mission failed (a goal not reached, or a collision in a scenario).\n";

}  // namespace

int run_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  const firmware::StopSignalsBlocked blocked;
  firmware::RunOptions options;
  if (int rc = firmware::parse_run_options(argc, argv, "sen3bot-sim", options, err); rc != 0) return rc;
  Result<SimulatedRobot> loaded = load_simulated_robot(options.config_path);
  if (!loaded) {
    std::fprintf(err, "sen3bot-sim: %s\n", loaded.error().c_str());
    return 2;
  }
  firmware::FirmwareConfig& config = loaded->firmware;
  firmware::apply(options, config);
  const SimulationConfig& world = loaded->world;
  Result<std::unique_ptr<SimBoard>> board = SimBoard::create(world, config.clock == firmware::ClockMode::lockstep);
  if (!board) {
    std::fprintf(err, "sen3bot-sim: %s: sim: %s\n", options.config_path.c_str(), board.error().c_str());
    return 1;
  }
  firmware::Firmware fw(config, **board, out);
  (*board)->referee().watch_estimate(&fw.pose_estimate());
  const int rc = firmware::run_firmware(fw, **board, config, out, err);
  std::fprintf(out, "\n");
  (*board)->referee().print(out);
  std::fflush(out);
  return rc;
}

int sim_cli_main(int argc, char** argv, std::FILE* out, std::FILE* err) {
  static constexpr firmware::Command kCommands[] = {
      {"run", "", run_command},
      {"sim", "", sim_command},
      {"experiment", "", experiment_command},
#ifdef SEN3BOT_HAS_RECOGNIZER
      {"train", "", train_command},
#endif
      {"fleet-sim", "", fleet_command},
#ifdef SEN3BOT_HAS_FORMATION
      {"formation", "", formation_command},
#endif
      {"agv", "", agv_command},
      {"slam-check", "", slam_check_command},
      {"can", "io", can_io_command},
      {"p2os-emulator", "", p2os_emulator_command},
      {"lms200-emulator", "", lms200_emulator_command},
  };
  return firmware::dispatch(argc, argv, "sen3bot-sim", SEN3BOT_VERSION, kUsage, kCommands, out, err);
}

}  // namespace sen3bot::sim
