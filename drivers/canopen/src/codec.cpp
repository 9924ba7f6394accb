#include "sen3bot/canopen/codec.hpp"

#include <array>

namespace sen3bot::canopen {

namespace {

constexpr std::uint32_t kNmt = 0x000;
constexpr std::uint32_t kSync = 0x080;
constexpr std::uint32_t kEmcy = 0x080;
constexpr std::uint32_t kSdoResponse = 0x580;
constexpr std::uint32_t kSdoRequest = 0x600;
constexpr std::uint32_t kHeartbeat = 0x700;
constexpr std::array<std::uint32_t, 4> kTpdo = {0x180, 0x280, 0x380, 0x480};
constexpr std::array<std::uint32_t, 4> kRpdo = {0x200, 0x300, 0x400, 0x500};

// SDO command specifiers (byte 0): the client's and server's command in bits 7..5, then for
// expedited transfers n (bits 3..2: 4 - size), e (bit 1) and s (bit 0).
constexpr std::uint8_t kCcsDownload = 1;  // client: initiate download
constexpr std::uint8_t kCcsUpload = 2;    // client: initiate upload
constexpr std::uint8_t kScsUpload = 2;    // server: initiate upload response
constexpr std::uint8_t kScsDownload = 3;  // server: initiate download response
constexpr std::uint8_t kCsAbort = 4;
constexpr std::uint8_t kExpedited = 0x02;
constexpr std::uint8_t kSizeGiven = 0x01;

Status check_node(std::uint8_t node, const char* what) {
  if (!valid_node(node))
    return Error::format(Errc::invalid_argument, "CANopen %s: node id %u is outside 1..127", what,
                         static_cast<unsigned>(node));
  return {};
}

CanFrame frame_of(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.dlc = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (const std::uint8_t b : bytes) f.data[i++] = b;
  return f;
}

CanFrame sdo_frame(std::uint32_t id, std::uint8_t command, SdoAddress at, std::uint32_t value) {
  return frame_of(id, {command, static_cast<std::uint8_t>(at.index & 0xFF), static_cast<std::uint8_t>(at.index >> 8),
                       at.sub, static_cast<std::uint8_t>(value & 0xFF), static_cast<std::uint8_t>((value >> 8) & 0xFF),
                       static_cast<std::uint8_t>((value >> 16) & 0xFF), static_cast<std::uint8_t>(value >> 24)});
}

Status check_size(std::uint8_t size, const char* what) {
  if (size < 1 || size > 4)
    return Error::format(Errc::invalid_argument, "CANopen %s: an expedited transfer carries 1..4 bytes, not %u", what,
                         static_cast<unsigned>(size));
  return {};
}

std::uint8_t expedited(std::uint8_t cs, std::uint8_t size) {
  return static_cast<std::uint8_t>(cs << 5 | (4 - size) << 2 | kExpedited | kSizeGiven);
}

std::uint32_t masked(std::uint32_t value, std::uint8_t size) {
  return size >= 4 ? value : value & ((1u << (8 * size)) - 1u);
}

// A plain 11-bit data frame: what every CANopen object is.
bool plain(const CanFrame& frame) noexcept { return !frame.extended && !frame.rtr && frame.id <= CanFrame::kMaxStandardId; }

Status short_frame(const CanFrame& frame, const char* what, std::uint8_t need) {
  return Error::format(Errc::protocol, "CANopen %s 0x%03X: %u data bytes, needs %u", what,
                       static_cast<unsigned>(frame.id), static_cast<unsigned>(frame.dlc), static_cast<unsigned>(need));
}
}  // namespace

const char* to_string(NmtCommand command) noexcept {
  switch (command) {
    case NmtCommand::start: return "start";
    case NmtCommand::stop: return "stop";
    case NmtCommand::enter_pre_operational: return "enter_pre_operational";
    case NmtCommand::reset_node: return "reset_node";
    case NmtCommand::reset_communication: return "reset_communication";
  }
  return "unknown";
}

const char* to_string(NmtState state) noexcept {
  switch (state) {
    case NmtState::boot_up: return "boot_up";
    case NmtState::stopped: return "stopped";
    case NmtState::operational: return "operational";
    case NmtState::pre_operational: return "pre_operational";
  }
  return "unknown";
}

const char* to_string(Kind kind) noexcept {
  switch (kind) {
    case Kind::nmt: return "nmt";
    case Kind::sync: return "sync";
    case Kind::emcy: return "emcy";
    case Kind::tpdo: return "tpdo";
    case Kind::rpdo: return "rpdo";
    case Kind::sdo_response: return "sdo_response";
    case Kind::sdo_request: return "sdo_request";
    case Kind::heartbeat: return "heartbeat";
    case Kind::other: return "other";
  }
  return "other";
}

const char* to_string(SdoType type) noexcept {
  switch (type) {
    case SdoType::upload_request: return "upload_request";
    case SdoType::download_request: return "download_request";
    case SdoType::upload_response: return "upload_response";
    case SdoType::download_response: return "download_response";
    case SdoType::abort: return "abort";
  }
  return "unknown";
}

Classified classify(const CanFrame& frame) noexcept {
  if (!plain(frame)) return {};
  const std::uint32_t id = frame.id;
  if (id == kNmt) return {Kind::nmt, 0, 0};
  if (id == kSync) return {Kind::sync, 0, 0};
  const std::uint32_t function = id & 0x780;
  const auto node = static_cast<std::uint8_t>(id & 0x7F);
  if (!valid_node(node)) return {};
  if (function == kEmcy) return {Kind::emcy, node, 0};
  for (std::uint8_t i = 0; i < 4; ++i) {
    if (function == kTpdo[i]) return {Kind::tpdo, node, static_cast<std::uint8_t>(i + 1)};
    if (function == kRpdo[i]) return {Kind::rpdo, node, static_cast<std::uint8_t>(i + 1)};
  }
  if (function == kSdoResponse) return {Kind::sdo_response, node, 0};
  if (function == kSdoRequest) return {Kind::sdo_request, node, 0};
  if (function == kHeartbeat) return {Kind::heartbeat, node, 0};
  return {};
}

Result<CanFrame> nmt(NmtCommand command, std::uint8_t node) {
  if (node != 0) {
    if (Status s = check_node(node, "NMT"); !s) return s.error();
  }
  return frame_of(kNmt, {static_cast<std::uint8_t>(command), node});
}

Result<CanFrame> heartbeat(std::uint8_t node, NmtState state) {
  if (Status s = check_node(node, "heartbeat"); !s) return s.error();
  return frame_of(kHeartbeat + node, {static_cast<std::uint8_t>(state)});
}

Result<CanFrame> pdo(std::uint8_t node, std::uint8_t number, bool transmit, std::span<const std::uint8_t> data) {
  if (Status s = check_node(node, "PDO"); !s) return s.error();
  if (number < 1 || number > 4)
    return Error::format(Errc::invalid_argument, "CANopen PDO: number %u is outside 1..4", static_cast<unsigned>(number));
  return CanFrame::make((transmit ? kTpdo : kRpdo)[number - 1] + node, data);
}

Result<CanFrame> emergency(std::uint8_t node, const Emergency& e) {
  if (Status s = check_node(node, "EMCY"); !s) return s.error();
  return frame_of(kEmcy + node, {static_cast<std::uint8_t>(e.code & 0xFF), static_cast<std::uint8_t>(e.code >> 8),
                                 e.error_register, e.vendor[0], e.vendor[1], e.vendor[2], e.vendor[3], e.vendor[4]});
}

const char* describe_emergency(std::uint16_t code) noexcept {
  switch (code) {
    case 0x0000: return "error reset or no error";
    case 0x8110: return "CAN overrun (objects lost)";
    case 0x8120: return "CAN in error passive mode";
    case 0x8130: return "heartbeat or life guard error";
    case 0x8140: return "recovered from bus off";
    case 0x8150: return "CAN-ID collision";
    case 0x8210: return "PDO not processed due to length error";
    case 0x8220: return "PDO length exceeded";
    case 0x8240: return "unexpected SYNC data length";
    case 0x8250: return "RPDO timeout";
    default: break;
  }
  switch (code >> 12) {
    case 0x1: return "generic error";
    case 0x2: return "current";
    case 0x3: return "voltage";
    case 0x4: return "temperature";
    case 0x5: return "device hardware";
    case 0x6: return "device software";
    case 0x7: return "additional modules";
    case 0x8: return "monitoring";
    case 0x9: return "external error";
    case 0xF: return (code >> 8) == 0xFF ? "device specific" : "additional functions";
    default: return "unknown error code";
  }
}

Result<CanFrame> sdo_upload_request(std::uint8_t node, SdoAddress at) {
  if (Status s = check_node(node, "SDO upload"); !s) return s.error();
  return sdo_frame(kSdoRequest + node, static_cast<std::uint8_t>(kCcsUpload << 5), at, 0);
}

Result<CanFrame> sdo_download_request(std::uint8_t node, SdoAddress at, std::uint32_t value, std::uint8_t size) {
  if (Status s = check_node(node, "SDO download"); !s) return s.error();
  if (Status s = check_size(size, "SDO download"); !s) return s.error();
  return sdo_frame(kSdoRequest + node, expedited(kCcsDownload, size), at, masked(value, size));
}

Result<CanFrame> sdo_abort(std::uint8_t node, SdoAddress at, std::uint32_t code, bool from_server) {
  if (Status s = check_node(node, "SDO abort"); !s) return s.error();
  return sdo_frame((from_server ? kSdoResponse : kSdoRequest) + node, static_cast<std::uint8_t>(kCsAbort << 5), at, code);
}

Result<CanFrame> sdo_upload_response(std::uint8_t node, SdoAddress at, std::uint32_t value, std::uint8_t size) {
  if (Status s = check_node(node, "SDO upload response"); !s) return s.error();
  if (Status s = check_size(size, "SDO upload response"); !s) return s.error();
  return sdo_frame(kSdoResponse + node, expedited(kScsUpload, size), at, masked(value, size));
}

Result<CanFrame> sdo_download_response(std::uint8_t node, SdoAddress at) {
  if (Status s = check_node(node, "SDO download response"); !s) return s.error();
  return sdo_frame(kSdoResponse + node, static_cast<std::uint8_t>(kScsDownload << 5), at, 0);
}

Result<Sdo> decode_sdo(const CanFrame& frame) {
  const Classified c = classify(frame);
  if (c.kind != Kind::sdo_request && c.kind != Kind::sdo_response)
    return Error::format(Errc::protocol, "CANopen: frame 0x%03X is not an SDO", static_cast<unsigned>(frame.id));
  if (frame.dlc < 8) return short_frame(frame, "SDO", 8).error();
  const bool request = c.kind == Kind::sdo_request;
  const std::uint8_t command = frame.data[0];
  const auto cs = static_cast<std::uint8_t>(command >> 5);
  Sdo sdo;
  sdo.node = c.node;
  sdo.at.index = static_cast<std::uint16_t>(frame.data[1] | frame.data[2] << 8);
  sdo.at.sub = frame.data[3];
  const std::uint32_t data = static_cast<std::uint32_t>(frame.data[4]) | static_cast<std::uint32_t>(frame.data[5]) << 8 |
                             static_cast<std::uint32_t>(frame.data[6]) << 16 |
                             static_cast<std::uint32_t>(frame.data[7]) << 24;
  // An expedited transfer with its size: (e, s) = (1, 1); n gives 4 - size.
  const auto expedited_size = [&](const char* what) -> Result<std::uint8_t> {
    if ((command & (kExpedited | kSizeGiven)) != (kExpedited | kSizeGiven))
      return Error::format(Errc::protocol,
                           "CANopen SDO %s 0x%04X:%u from node %u: command 0x%02X is a segmented transfer (only "
                           "expedited ones are spoken)",
                           what, static_cast<unsigned>(sdo.at.index), static_cast<unsigned>(sdo.at.sub),
                           static_cast<unsigned>(c.node), static_cast<unsigned>(command));
    return static_cast<std::uint8_t>(4 - ((command >> 2) & 0x3));
  };
  if (cs == kCsAbort) {
    sdo.type = SdoType::abort;
    sdo.value = data;
    return sdo;
  }
  if (request && cs == kCcsUpload) {
    sdo.type = SdoType::upload_request;
    return sdo;
  }
  if (request && cs == kCcsDownload) {
    Result<std::uint8_t> size = expedited_size("download");
    if (!size) return size.error();
    sdo.type = SdoType::download_request;
    sdo.size = *size;
    sdo.value = masked(data, sdo.size);
    return sdo;
  }
  if (!request && cs == kScsUpload) {
    Result<std::uint8_t> size = expedited_size("upload response");
    if (!size) return size.error();
    sdo.type = SdoType::upload_response;
    sdo.size = *size;
    sdo.value = masked(data, sdo.size);
    return sdo;
  }
  if (!request && cs == kScsDownload) {
    sdo.type = SdoType::download_response;
    return sdo;
  }
  return Error::format(Errc::protocol, "CANopen SDO %s from node %u: command 0x%02X is not spoken",
                       request ? "request" : "response", static_cast<unsigned>(c.node), static_cast<unsigned>(command));
}

const char* describe_abort(std::uint32_t code) noexcept {
  switch (code) {
    case 0x0503'0000: return "toggle bit not alternated";
    case 0x0504'0000: return "SDO protocol timed out";
    case 0x0504'0001: return "client/server command specifier not valid or unknown";
    case 0x0504'0002: return "invalid block size";
    case 0x0504'0003: return "invalid sequence number";
    case 0x0504'0004: return "CRC error";
    case 0x0504'0005: return "out of memory";
    case 0x0601'0000: return "unsupported access to an object";
    case 0x0601'0001: return "attempt to read a write only object";
    case 0x0601'0002: return "attempt to write a read only object";
    case 0x0602'0000: return "object does not exist in the object dictionary";
    case 0x0604'0041: return "object cannot be mapped to the PDO";
    case 0x0604'0042: return "the number and length of the objects to be mapped would exceed PDO length";
    case 0x0604'0043: return "general parameter incompatibility";
    case 0x0604'0047: return "general internal incompatibility in the device";
    case 0x0606'0000: return "access failed due to a hardware error";
    case 0x0607'0010: return "data type does not match, length of service parameter does not match";
    case 0x0607'0012: return "data type does not match, length of service parameter too high";
    case 0x0607'0013: return "data type does not match, length of service parameter too low";
    case 0x0609'0011: return "sub-index does not exist";
    case 0x0609'0030: return "invalid value for parameter";
    case 0x0609'0031: return "value of parameter written too high";
    case 0x0609'0032: return "value of parameter written too low";
    case 0x0609'0036: return "maximum value is less than minimum value";
    case 0x060A'0023: return "resource not available: SDO connection";
    case 0x0800'0000: return "general error";
    case 0x0800'0020: return "data cannot be transferred or stored to the application";
    case 0x0800'0021: return "data cannot be transferred or stored to the application because of local control";
    case 0x0800'0022: return "data cannot be transferred or stored to the application because of the present device state";
    case 0x0800'0023: return "object dictionary dynamic generation fails or no object dictionary is present";
    case 0x0800'0024: return "no data available";
    default: return "unknown abort code";
  }
}

Result<Nmt> decode_nmt(const CanFrame& frame) {
  if (classify(frame).kind != Kind::nmt)
    return Error::format(Errc::protocol, "CANopen: frame 0x%03X is not NMT", static_cast<unsigned>(frame.id));
  if (frame.dlc < 2) return short_frame(frame, "NMT", 2).error();
  const std::uint8_t command = frame.data[0];
  switch (command) {
    case 0x01:
    case 0x02:
    case 0x80:
    case 0x81:
    case 0x82:
      break;
    default:
      return Error::format(Errc::protocol, "CANopen NMT: command 0x%02X is not one of CiA 301's",
                           static_cast<unsigned>(command));
  }
  if (frame.data[1] > kMaxNode)
    return Error::format(Errc::protocol, "CANopen NMT: node id %u is outside 0..127", static_cast<unsigned>(frame.data[1]));
  return Nmt{static_cast<NmtCommand>(command), frame.data[1]};
}

Result<Heartbeat> decode_heartbeat(const CanFrame& frame) {
  const Classified c = classify(frame);
  if (c.kind != Kind::heartbeat)
    return Error::format(Errc::protocol, "CANopen: frame 0x%03X is not a heartbeat", static_cast<unsigned>(frame.id));
  if (frame.dlc < 1) return short_frame(frame, "heartbeat", 1).error();
  const auto state = static_cast<std::uint8_t>(frame.data[0] & 0x7F);
  switch (state) {
    case 0x00:
    case 0x04:
    case 0x05:
    case 0x7F:
      break;
    default:
      return Error::format(Errc::protocol, "CANopen heartbeat from node %u: state 0x%02X is not one of CiA 301's",
                           static_cast<unsigned>(c.node), static_cast<unsigned>(state));
  }
  return Heartbeat{c.node, static_cast<NmtState>(state), (frame.data[0] & 0x80) != 0};
}

Result<Emergency> decode_emergency(const CanFrame& frame) {
  const Classified c = classify(frame);
  if (c.kind != Kind::emcy)
    return Error::format(Errc::protocol, "CANopen: frame 0x%03X is not an EMCY", static_cast<unsigned>(frame.id));
  if (frame.dlc < 8) return short_frame(frame, "EMCY", 8).error();
  Emergency e;
  e.code = static_cast<std::uint16_t>(frame.data[0] | frame.data[1] << 8);
  e.error_register = frame.data[2];
  for (std::size_t i = 0; i < e.vendor.size(); ++i) e.vendor[i] = frame.data[3 + i];
  return e;
}

}  // namespace sen3bot::canopen
