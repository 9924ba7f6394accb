#pragma once
// The simulator's commands; sim_cli.cpp dispatches to them. Each takes the arguments after its
// command word and returns the exit status (0 success, 1 run-time failure, 2 bad command line,
// 3 a mission or a scenario case failed). `experiment` returns 0 when its runs completed,
// whatever they measured.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace sen3bot::sim {

// The whole command line of sen3bot-sim.
int sim_cli_main(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim run --config FILE [--duration S] [--clock lockstep|realtime]
int run_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim sim --scenario NAME [--config FILE] [--realtime] [--seed N] [--report DIR]
int sim_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sim --scenario cobot [--attempts N] [--case NAME]: the collaborative mode's scenario (cmd_cobot.cpp).
int cobot_scenario(const std::string& config_path, const std::string& report_dir, std::uint64_t seed, bool have_seed,
                   std::size_t attempts, const std::string& only, std::FILE* out, std::FILE* err);
void list_cobot_scenario(std::FILE* out);
// sen3bot-sim experiment dol --speed M_S --runs N [--boxes K] [--no-dol] [--no-prediction]
//   [--no-baseline] [--seed S] [--jobs J] [--report DIR] [--config FILE]
int experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim experiment crowd (--scene NAME [--people N] [--behaviour B] | --trajectories FILE)
//   --runs N [--seed S] [--jobs J] [--variant default|no-people]... [--report DIR] [--config FILE]
int crowd_experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim experiment operations --runs N [--report DIR] [--seed S] [--model M] [--operations O]
//   [--save-paths FILE] [--style NAME] [--first-task] [--no-baseline] [--baseline-per-class N]
int operations_experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim train operations --out MODEL [--per-class N] [--seed S] [--operations O] [--hidden N]
//   [--encoding occupancy|occupancy_order] [--references FILE]
int train_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim fleet-sim --scenario net-1|net-2|net-3 [--report DIR] [--site FILE] [--config FILE]
int fleet_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim formation --example 1|2|3 [--report DIR] [--runs N] [--seed S] [--duration S] [--config FILE]
int formation_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim agv --broker URL --serial S [--manufacturer M] [--map-id ID] [--speed M_S] [--x X --y Y --theta RAD]
//   [--duration S] [--username U --password-file F --ca-file F] [--client-id ID]
int agv_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim slam-check --carmen LOG [--poses NAME=FILE ...] [--odometry] [--figure DIR] [--min-gap N]
//   [--max-distance M]: mapping trajectories' consistency between scans far apart in time (cmd_slam_check.cpp)
int slam_check_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim can io --iface sim --node N [--set OUT=0|1 ...] [--timeout S] [--sim-inputs 0xHH]
//   [--sim-silent]: the robot's can io against the emulated CiA 401 node (cmd_can_io.cpp)
int can_io_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim p2os-emulator (--pty LINK | --tcp PORT) [--name NAME] [--watchdog stop|resume]
int p2os_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot-sim lms200-emulator --pty LINK [--map MAP.yaml --pose X,Y,TH] [--baud B] [--variant A/R]
//   [--units cm|mm] [--mode M] [--indices on|off] [--status S] [--fault F]... (lms200_emulator_options.hpp)
int lms200_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err);

}  // namespace sen3bot::sim
