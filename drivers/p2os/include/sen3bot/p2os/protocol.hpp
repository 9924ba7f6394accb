#pragma once
// P2OS / ARCOS wire format (Pioneer 3-DX microcontroller, RS-232 HOST port or TCP 8101).
//
// Frame, both directions:
//
//   offset 0      0xFA                 header byte 1
//   offset 1      0xFB                 header byte 2
//   offset 2      N                    bytes that follow: type + payload + 2 checksum bytes;
//                                      3 <= N (N < 3 is rejected); frame length is N + 3
//   offset 3      type / command       server packet type, or client command number
//   offset 4..    payload              N - 3 bytes; multi-byte fields little-endian
//   offset N+1    checksum high byte   the checksum is sent big-endian, unlike the data
//   offset N+2    checksum low byte
//
// Checksum over the N - 2 bytes from offset 3: the 16-bit sum of big-endian byte pairs,
// and an odd last byte XORed into the low byte.
//
// Client command arguments (after the command byte):
//   0x3B lo hi      ARGINT: value = +(hi<<8 | lo)
//   0x1B lo hi      ARGNINT: value = -(hi<<8 | lo)
//   0x2B n bytes    ARGSTR: n bytes (ARIA adds a NUL that n does not count)
//
// Handshake: SYNC0, SYNC1 echoed; SYNC2 answered with type 2 carrying three NUL-terminated
// strings (name, "Pioneer", "p3dx-sh"); then OPEN starts a SIP every SipCycle (100 ms).
//
// Standard SIP, type 0x32 (stopped) / 0x33 (moving), offsets from the type byte (payload
// offset = frame offset - 4):
//   frame  4  XPOS        uint16, 15 LS bits used, mm (x DistConvFactor)
//          6  YPOS        uint16, 15 LS bits used
//          8  THPOS       int16, 4096ths of a revolution
//         10  L VEL       int16 mm/s (x VelConvFactor)
//         12  R VEL       int16 mm/s
//         14  BATTERY     uint8, volts x 10
//         15  STALLBUMP   uint16: bit 0 left stall, 1-7 rear bumpers, 8 right stall, 9-15 front
//         17  CONTROL     int16, heading servo setpoint (4096ths)
//         19  FLAGS       uint16: bit 0 motors, 1-4 sonar arrays, 5 e-stop, 6 e-stall, ...
//         21  COMPASS     uint8, 2-degree units
//         22  SONARCOUNT  uint8 n, then n x (disc uint8, range uint16 mm)
//   23+3n     GRIP_STATE, ANPORT, ANALOG, DIGIN, DIGOUT (uint8 each)
//   +5        BATTERYX10 uint16, +7 CHARGESTATE int8, +8 ROTVEL int16 (deg/s x 10),
//   +10       FAULTFLAGS uint16, +12 LATVEL int16, +14 TEMPERATURE int8, +15 SOC uint8:
//             all optional; read only when present.
//
// CONFIGpac 0x20: see ConfigPacket (codec.hpp) for the field order.
// ENCODERpac 0x90: left int32 LE, right int32 LE (a 9-byte body, odd-length checksum).
#include <cstddef>
#include <cstdint>

namespace sen3bot::p2os {

inline constexpr std::uint8_t kHeader1 = 0xFA;
inline constexpr std::uint8_t kHeader2 = 0xFB;
inline constexpr std::size_t kHeaderBytes = 3;    // FA FB N
inline constexpr std::size_t kChecksumBytes = 2;
inline constexpr std::uint8_t kMinCount = 3;      // type + 2 checksum bytes
// N is one byte; frames up to 258 bytes are accepted on receive.
inline constexpr std::size_t kMaxFrameBytes = 255 + kHeaderBytes;
// ARCOS ignores client packets with N > 204 and clients assume <= 200: we emit frames <= 200.
inline constexpr std::size_t kMaxEmitFrameBytes = 200;
inline constexpr std::size_t kMaxBodyBytes = 255 - kChecksumBytes;  // type + payload

// ARIA gives up on a partly received packet after this gap between bytes.
inline constexpr std::int64_t kInterByteGapMs = 100;

// Argument type bytes.
inline constexpr std::uint8_t kArgInt = 0x3B;
inline constexpr std::uint8_t kArgNegInt = 0x1B;
inline constexpr std::uint8_t kArgString = 0x2B;
// ARIA's comStr limit; we cap SAY and other strings well below the frame limit.
inline constexpr std::size_t kMaxStringArgBytes = 190;

// Client command numbers (ARIA ArCommands.h, Player p2os.h, ARCOS manual).
enum class Command : std::uint8_t {
  sync0 = 0,  // also PULSE once connected
  sync1 = 1,  // also OPEN
  sync2 = 2,  // also CLOSE
  polling = 3,
  enable = 4,
  seta = 5,
  setv = 6,
  seto = 7,
  move = 8,
  rotate = 9,
  setrv = 10,
  vel = 11,
  head = 12,
  dhead = 13,
  say = 15,
  joyinfo = 17,
  config = 18,
  encoder = 19,
  setrvdir = 20,
  rvel = 21,
  dchead = 22,
  setra = 23,
  sonar = 28,
  stop = 29,
  digout = 30,
  vel2 = 32,
  gripper = 33,
  adsel = 35,
  ioreq = 40,
  tty2 = 42,
  getaux = 43,
  bumpstall = 44,
  joydrive = 47,
  sonarcycle = 48,
  hostbaud = 50,
  estop = 55,
  e_stall = 56,
  batteryinfo = 62,
  battest = 250,
  reset = 253,
  maintenance = 255,
};
inline constexpr Command kPulse = Command::sync0;
inline constexpr Command kOpen = Command::sync1;
inline constexpr Command kClose = Command::sync2;

// Server packet types.
inline constexpr std::uint8_t kTypeSync0 = 0x00;
inline constexpr std::uint8_t kTypeSync1 = 0x01;
inline constexpr std::uint8_t kTypeSync2 = 0x02;
inline constexpr std::uint8_t kTypeConfig = 0x20;
inline constexpr std::uint8_t kTypeSipStopped = 0x32;
inline constexpr std::uint8_t kTypeSipMoving = 0x33;
inline constexpr std::uint8_t kTypeEncoder = 0x90;
inline constexpr std::uint8_t kTypeResetA = 0xFE;  // controller reset (ARIA drops the link)
inline constexpr std::uint8_t kTypeResetB = 0xFF;

// Standard SIP field offsets within the body (type byte = 0).
namespace sip {
inline constexpr std::size_t kX = 1;
inline constexpr std::size_t kY = 3;
inline constexpr std::size_t kTheta = 5;
inline constexpr std::size_t kLeftVel = 7;
inline constexpr std::size_t kRightVel = 9;
inline constexpr std::size_t kBattery = 11;
inline constexpr std::size_t kStallBump = 12;
inline constexpr std::size_t kControl = 14;
inline constexpr std::size_t kFlags = 16;
inline constexpr std::size_t kCompass = 18;
inline constexpr std::size_t kSonarCount = 19;
inline constexpr std::size_t kSonarFirst = 20;
inline constexpr std::size_t kSonarEntryBytes = 3;
inline constexpr std::size_t kFixedBytes = 20;  // type through SONARCOUNT
inline constexpr std::size_t kGripTailBytes = 5;  // GRIP_STATE .. DIGOUT, required after sonar
}  // namespace sip

// FLAGS bits (ARCOS manual table 8).
namespace flags {
inline constexpr std::uint16_t kMotorsEnabled = 1u << 0;
inline constexpr std::uint16_t kSonarArrays = 0x1Eu;  // bits 1-4
inline constexpr std::uint16_t kEStop = 1u << 5;
inline constexpr std::uint16_t kEStall = 1u << 6;
}  // namespace flags

// Odometry units.
inline constexpr std::uint16_t kPositionMask = 0x7FFF;  // x/y are 15-bit wrapping counters
inline constexpr std::int32_t kPositionModulus = 0x8000;
inline constexpr std::int32_t kPositionUnwrapWindow = 0x1000;  // ARIA's delta window
inline constexpr std::int32_t kThetaUnitsPerRev = 4096;

// HOSTBAUD argument codes.
inline constexpr std::uint32_t kHostBaudRates[] = {9600, 19200, 38400, 57600, 115200};

}  // namespace sen3bot::p2os
