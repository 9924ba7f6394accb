#pragma once
// Device command-line entry points, one function per command; cli.cpp dispatches to them.
// Each takes the arguments after its command words and returns the process exit code
// (0 success, 1 run-time failure, 2 bad command line).
#include <cstdio>

namespace sen3bot::firmware {

// sen3bot decode p2os CAPTURE
int decode_p2os_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot drive --port DEV|tcp://HOST:PORT --vel M_S --rvel RAD_S --seconds S
int drive_command(int argc, char** argv, std::FILE* out, std::FILE* err);

// sen3bot decode lms200 CAPTURE
int decode_lms200_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot scan --port DEV --baud B --variant A/R --units cm|mm --count N
int scan_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot camera probe URL [--transport tcp|udp] [--frames N] [--save DIR] [--timeout S]
int camera_command(int argc, char** argv, std::FILE* out, std::FILE* err);

// sen3bot can dump SOURCE [--node N] [--count N]  (SOURCE: candump -l log, -, or a SocketCAN interface)
int can_dump_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot can io --iface IFACE --node N [--set OUT=0|1 ...] [--timeout S]  (the emulated node:
// sen3bot-sim can io --iface sim; can_io.hpp)
int can_io_command(int argc, char** argv, std::FILE* out, std::FILE* err);

// sen3bot map --carmen FILE --out DIR/NAME.yaml [--resolution R] [--poses FILE]
int map_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot plan --map MAP.yaml --start X,Y --goal X,Y [--waypoints FILE] [--unit-cost]
int plan_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot sgp --map MAP.yaml --curve CURVE.yaml --start X,Y --goal X,Y [--direction 1|-1] [--png FILE]
int sgp_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot fuse --capture SCANS.s3bcap --boxes BOXES.jsonl [--map MAP.yaml] [--pose X,Y,THETA_DEG] [--window S]
//              [--offset S]
int fuse_command(int argc, char** argv, std::FILE* out, std::FILE* err);
// sen3bot detect --image FILE [--scale S] [--threshold T] [--repeat N] [--png FILE]
int detect_command(int argc, char** argv, std::FILE* out, std::FILE* err);

// sen3bot recognize --paths FILE [--progressive] [--model M] [--operations O]
int recognize_command(int argc, char** argv, std::FILE* out, std::FILE* err);

// sen3bot cobot tags --operator ID --out DIR [--module-px N]
int cobot_command(int argc, char** argv, std::FILE* out, std::FILE* err);

}  // namespace sen3bot::firmware
