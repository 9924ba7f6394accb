#pragma once
// CANopen (CiA 301) frames for one master and its nodes, as a pure codec: no bus, no clock.
// The pre-defined connection set: COB-ID = function code + node id (1..127), 11-bit ids.
//   NMT 0x000 (master: command, node; 0 = all), SYNC 0x080, EMCY 0x080 + id,
//   TPDO1..4 0x180/0x280/0x380/0x480 + id (node to master), RPDO1..4 0x200/0x300/0x400/0x500 + id,
//   SDO response 0x580 + id, SDO request 0x600 + id, heartbeat and boot-up 0x700 + id.
// Only expedited SDO (up to 4 data bytes) is spoken: a CiA 401 I/O node's configuration fits.
// Every decoder takes any frame and says what is wrong with a malformed one, never throws and
// never reads past the frame's dlc.
#include <cstdint>
#include <optional>
#include <string_view>

#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::canopen {

using hal::CanFrame;

constexpr std::uint8_t kMinNode = 1;
constexpr std::uint8_t kMaxNode = 127;
[[nodiscard]] constexpr bool valid_node(unsigned node) noexcept { return node >= kMinNode && node <= kMaxNode; }

enum class NmtCommand : std::uint8_t {
  start = 0x01,
  stop = 0x02,
  enter_pre_operational = 0x80,
  reset_node = 0x81,
  reset_communication = 0x82,
};
[[nodiscard]] const char* to_string(NmtCommand command) noexcept;

// The state a heartbeat reports; boot_up is the one frame a node sends after a reset.
enum class NmtState : std::uint8_t {
  boot_up = 0x00,
  stopped = 0x04,
  operational = 0x05,
  pre_operational = 0x7F,
};
[[nodiscard]] const char* to_string(NmtState state) noexcept;

// What a frame is, by its COB-ID alone (an 11-bit data frame).
enum class Kind : std::uint8_t {
  nmt,
  sync,
  emcy,
  tpdo,  // node to master, pdo 1..4
  rpdo,  // master to node, pdo 1..4
  sdo_response,
  sdo_request,
  heartbeat,
  other,  // extended ids, remote frames, ids outside the connection set
};
[[nodiscard]] const char* to_string(Kind kind) noexcept;

struct Classified {
  Kind kind = Kind::other;
  std::uint8_t node = 0;  // 0 for NMT and SYNC
  std::uint8_t pdo = 0;   // 1..4 for tpdo/rpdo
};
[[nodiscard]] Classified classify(const CanFrame& frame) noexcept;

// --- Encoders (the node ids are checked: Errc::invalid_argument outside 1..127) ----------------

// node 0 addresses every node.
[[nodiscard]] Result<CanFrame> nmt(NmtCommand command, std::uint8_t node);
[[nodiscard]] Result<CanFrame> heartbeat(std::uint8_t node, NmtState state);
// A PDO (1..4) of up to 8 bytes; transmit = the node's TPDO, else the RPDO it receives.
[[nodiscard]] Result<CanFrame> pdo(std::uint8_t node, std::uint8_t number, bool transmit,
                                        std::span<const std::uint8_t> data);

struct Emergency {
  std::uint16_t code = 0;       // 0x0000: error reset
  std::uint8_t error_register = 0;  // object 0x1001
  std::array<std::uint8_t, 5> vendor{};
};
[[nodiscard]] Result<CanFrame> emergency(std::uint8_t node, const Emergency& e);
// The class of an EMCY error code (CiA 301 table), e.g. "heartbeat or life guard error".
[[nodiscard]] const char* describe_emergency(std::uint16_t code) noexcept;

// --- SDO, expedited ----------------------------------------------------------------------------

struct SdoAddress {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  friend bool operator==(const SdoAddress&, const SdoAddress&) = default;
};

// Client (master) requests to the node's server.
[[nodiscard]] Result<CanFrame> sdo_upload_request(std::uint8_t node, SdoAddress at);
// size 1..4 bytes of value, little-endian.
[[nodiscard]] Result<CanFrame> sdo_download_request(std::uint8_t node, SdoAddress at, std::uint32_t value,
                                                         std::uint8_t size);
[[nodiscard]] Result<CanFrame> sdo_abort(std::uint8_t node, SdoAddress at, std::uint32_t code, bool from_server);

// The server's answers (what a node sends back), and what the emulator needs to build them.
[[nodiscard]] Result<CanFrame> sdo_upload_response(std::uint8_t node, SdoAddress at, std::uint32_t value,
                                                        std::uint8_t size);
[[nodiscard]] Result<CanFrame> sdo_download_response(std::uint8_t node, SdoAddress at);

enum class SdoType : std::uint8_t {
  upload_request,     // client: read
  download_request,   // client: write value (size bytes)
  upload_response,    // server: the value read (size bytes)
  download_response,  // server: written
  abort,              // either side: abort_code
};
[[nodiscard]] const char* to_string(SdoType type) noexcept;

struct Sdo {
  SdoType type = SdoType::abort;
  std::uint8_t node = 0;
  SdoAddress at;
  std::uint32_t value = 0;  // the data, or the abort code
  std::uint8_t size = 0;    // data bytes, 1..4 (0 for requests without data and answers without)
};
// An SDO request (0x600 + id) or response (0x580 + id). Errc::protocol for a segmented or
// block transfer (not spoken), a reserved command, a short frame or a size out of range.
[[nodiscard]] Result<Sdo> decode_sdo(const CanFrame& frame);
// The CiA 301 text of an abort code, e.g. "object does not exist in the object dictionary";
// "unknown abort code" otherwise.
[[nodiscard]] const char* describe_abort(std::uint32_t code) noexcept;

// Abort codes the master and the emulator use by name.
namespace abort_code {
constexpr std::uint32_t kToggleBit = 0x0503'0000;
constexpr std::uint32_t kTimedOut = 0x0504'0000;
constexpr std::uint32_t kBadCommand = 0x0504'0001;
constexpr std::uint32_t kWriteOnly = 0x0601'0001;
constexpr std::uint32_t kReadOnly = 0x0601'0002;
constexpr std::uint32_t kNoObject = 0x0602'0000;
constexpr std::uint32_t kLengthMismatch = 0x0607'0010;
constexpr std::uint32_t kNoSubIndex = 0x0609'0011;
constexpr std::uint32_t kValueRange = 0x0609'0030;
constexpr std::uint32_t kGeneral = 0x0800'0000;
}  // namespace abort_code

// --- Other decoders ----------------------------------------------------------------------------

struct Nmt {
  NmtCommand command = NmtCommand::start;
  std::uint8_t node = 0;  // 0: all nodes
};
[[nodiscard]] Result<Nmt> decode_nmt(const CanFrame& frame);

struct Heartbeat {
  std::uint8_t node = 0;
  NmtState state = NmtState::boot_up;
  bool toggle = false;  // bit 7, used by node guarding only
};
[[nodiscard]] Result<Heartbeat> decode_heartbeat(const CanFrame& frame);

[[nodiscard]] Result<Emergency> decode_emergency(const CanFrame& frame);

}  // namespace sen3bot::canopen
