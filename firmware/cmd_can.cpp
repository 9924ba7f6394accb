// CAN command-line tools: `can dump` decodes a candump log (or a live SocketCAN bus) as
// CANopen JSON lines, `can io` brings one CiA 401 I/O node up with the master's state machine,
// sets its outputs and prints its inputs (on a SocketCAN bus; against the emulated node it is
// `sen3bot-sim can io --iface sim`, which runs the same code).
#include <poll.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "can_io.hpp"
#include "cli_util.hpp"
#include "commands.hpp"
#include "sen3bot/canopen/codec.hpp"
#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/candump.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::firmware {

namespace {

using canopen::Classified;
using canopen::Kind;
using hal::CanFrame;

constexpr const char* kDumpUsage =
    "usage: sen3bot can dump SOURCE [--node N] [--count N]\n"
    "  SOURCE: a candump -l log file, - for standard input, or a SocketCAN interface\n";
constexpr const char* kIoUsage =
    "usage: sen3bot can io --iface IFACE --node N [--set OUT=0|1 ...] [--timeout S]\n";

[[gnu::format(printf, 2, 3)]] void append(std::string& out, const char* fmt, ...) {
  char text[256];
  va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(text, sizeof text, fmt, args);
  va_end(args);
  if (n > 0) out.append(text, std::min(static_cast<std::size_t>(n), sizeof text - 1));
}

[[gnu::format(printf, 1, 2)]] std::string printed(const char* fmt, ...) {
  char text[64];
  va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(text, sizeof text, fmt, args);
  va_end(args);
  return n > 0 ? std::string(text, std::min(static_cast<std::size_t>(n), sizeof text - 1)) : std::string();
}

void member_hex(json::Writer& w, std::string_view key, std::span<const std::uint8_t> bytes) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string hex;
  for (const std::uint8_t b : bytes) {
    hex += kHex[b >> 4];
    hex += kHex[b & 0xF];
  }
  w.member(key, hex);
}

// The 8 bits of a CiA 401 digital byte: "0x05" and the numbers (1..8) of the bits that are set.
void write_bits(json::Writer& w, std::string_view key, std::uint8_t bits) {
  w.member(key, printed("0x%02X", static_cast<unsigned>(bits)));
  w.key(std::string(key) + "_on").begin_array();
  for (unsigned i = 0; i < 8; ++i) {
    if ((bits >> i & 1u) != 0) w.uint32(i + 1);
  }
  w.end_array();
}

// Seconds as candump writes them (microseconds), exact rather than through a double.
void member_time(json::Writer& w, std::int64_t unix_ns) {
  w.key("t_s").raw(printed("%lld.%06lld", static_cast<long long>(unix_ns / 1'000'000'000),
                           static_cast<long long>(unix_ns % 1'000'000'000 / 1000)));
}

// --- Error frames --------------------------------------------------------------------------

struct Bit {
  std::uint32_t bit;
  const char* name;
};
constexpr std::array<Bit, 9> kErrorClasses = {{
    {hal::can_error::kTxTimeout, "tx_timeout"},
    {hal::can_error::kLostArbitration, "lost_arbitration"},
    {hal::can_error::kController, "controller"},
    {hal::can_error::kProtocol, "protocol"},
    {hal::can_error::kTransceiver, "transceiver"},
    {hal::can_error::kNoAck, "no_ack"},
    {hal::can_error::kBusOff, "bus_off"},
    {hal::can_error::kBusError, "bus_error"},
    {hal::can_error::kRestarted, "restarted"},
}};
constexpr std::array<Bit, 7> kControllerStates = {{
    {hal::can_error::kRxOverflow, "rx_overflow"},
    {hal::can_error::kTxOverflow, "tx_overflow"},
    {hal::can_error::kRxWarning, "rx_warning"},
    {hal::can_error::kTxWarning, "tx_warning"},
    {hal::can_error::kRxPassive, "rx_passive"},
    {hal::can_error::kTxPassive, "tx_passive"},
    {hal::can_error::kActive, "active"},
}};

template <std::size_t N>
void write_names(json::Writer& w, std::string_view key, std::uint32_t bits, const std::array<Bit, N>& names) {
  w.key(key).begin_array();
  std::uint32_t known = 0;
  for (const Bit& b : names) {
    known |= b.bit;
    if ((bits & b.bit) != 0) w.string(b.name);
  }
  // Bits Linux may add later are shown rather than dropped.
  if ((bits & ~known) != 0) w.string(printed("0x%X", static_cast<unsigned>(bits & ~known)));
  w.end_array();
}

// The link state one error frame leads to, by the SocketCAN backend's own rule
// (hal::next_link_state), or nothing when the frame leaves every state as it was.
std::optional<hal::CanLinkState> link_after(const CanFrame& f) {
  const hal::CanLinkState from_off = hal::next_link_state(hal::CanLinkState::bus_off, f);
  if (from_off == hal::CanLinkState::bus_off &&
      hal::next_link_state(hal::CanLinkState::active, f) == hal::CanLinkState::active)
    return std::nullopt;
  return from_off;
}

void describe_error_frame(json::Writer& w, const CanFrame& f) {
  w.member("kind", "error");
  write_names(w, "events", f.id, kErrorClasses);
  if ((f.id & hal::can_error::kController) != 0 && f.dlc >= 2) write_names(w, "controller", f.data[1], kControllerStates);
  if (const std::optional<hal::CanLinkState> link = link_after(f)) w.member("link", hal::to_string(*link));
  member_hex(w, "data", f.payload());
}

// --- CANopen ---------------------------------------------------------------------------------

void describe_canopen(json::Writer& w, const CanFrame& f, const Classified& c) {
  w.member("kind", canopen::to_string(c.kind));
  if (c.node != 0) w.member_uint32("node", c.node);
  if (c.kind == Kind::tpdo || c.kind == Kind::rpdo) w.member_uint32("pdo", c.pdo);
  if (f.extended) w.member_bool("extended", true);
  if (f.rtr) w.member_bool("rtr", true).member_uint32("dlc", f.dlc);
  else member_hex(w, "data", f.payload());
  const auto malformed = [&](const Error& e) { w.member("malformed", e.message()); };
  switch (c.kind) {
    case Kind::nmt:
      if (auto n = canopen::decode_nmt(f)) {
        w.member("command", canopen::to_string(n->command)).member_uint32("target", n->node);
      } else {
        malformed(n.error());
      }
      break;
    case Kind::heartbeat:
      if (auto h = canopen::decode_heartbeat(f)) {
        w.member("state", canopen::to_string(h->state));
        if (h->toggle) w.member_bool("toggle", true);
      } else {
        malformed(h.error());
      }
      break;
    case Kind::emcy:
      if (auto e = canopen::decode_emergency(f)) {
        w.member("code", printed("0x%04X", static_cast<unsigned>(e->code)))
            .member("register", printed("0x%02X", static_cast<unsigned>(e->error_register)))
            .member("description", canopen::describe_emergency(e->code));
        member_hex(w, "vendor", e->vendor);
      } else {
        malformed(e.error());
      }
      break;
    case Kind::sdo_request:
    case Kind::sdo_response:
      if (auto s = canopen::decode_sdo(f)) {
        w.member("sdo", canopen::to_string(s->type))
            .member("index", printed("0x%04X", static_cast<unsigned>(s->at.index)))
            .member_uint32("sub", s->at.sub);
        if (s->type == canopen::SdoType::abort) {
          w.member("abort_code", printed("0x%08X", static_cast<unsigned>(s->value)))
              .member("abort", canopen::describe_abort(s->value));
        } else if (s->size > 0) {
          w.member_uint32("size", s->size).member_uint64("value", s->value);
        }
      } else {
        malformed(s.error());
      }
      break;
    case Kind::tpdo:
    case Kind::rpdo:
      // PDO1's first byte is the 8 digital inputs (TPDO1) or outputs (RPDO1) of a CiA 401
      // node's default mapping: what the robot's I/O node sends.
      if (c.pdo == 1 && !f.rtr && f.dlc >= 1) write_bits(w, c.kind == Kind::tpdo ? "inputs" : "outputs", f.data[0]);
      break;
    case Kind::sync:
      if (f.dlc >= 1 && !f.rtr) w.member_uint32("counter", f.data[0]);
      break;
    case Kind::other:
      break;
  }
}

// One frame as a JSON object, without its newline.
std::string describe_frame_json(std::int64_t unix_ns, std::string_view interface, const CanFrame& f, bool error_frame) {
  std::string out;
  out.reserve(256);
  json::StringSink sink(out);
  json::Writer w(sink);
  w.begin_object();
  member_time(w, unix_ns);
  w.member("interface", interface);
  const std::uint32_t logged_id = error_frame ? (f.id | hal::can_error::kFlag) : f.id;
  w.member("id", printed(f.extended ? "%08X" : "%03X", static_cast<unsigned>(logged_id)));
  if (error_frame) {
    describe_error_frame(w, f);
  } else {
    describe_canopen(w, f, canopen::classify(f));
  }
  w.end_object();
  return out;
}

// --node N: that node's frames, NMT commands to it or to all, and the link's error frames
// (a bus-off silences every node, so it is kept).
bool keep_for_node(const CanFrame& f, bool error_frame, unsigned node) {
  if (error_frame) return true;
  const Classified c = canopen::classify(f);
  if (c.kind == Kind::nmt) return f.dlc < 2 || f.data[1] == 0 || f.data[1] == node;
  return c.node == node;
}

struct DumpOptions {
  std::string source;
  unsigned node = 0;  // 0: every frame
  std::uint64_t count = 0;  // 0: no limit
};

void print_line(std::FILE* out, const std::string& line) {
  std::fputs(line.c_str(), out);
  std::fputc('\n', out);
}

// A log file (or stdin): one object per frame, one per bad line with its number and what is
// wrong with it. Exit status 1 when a line was bad.
int dump_log(std::FILE* in, const DumpOptions& o, std::FILE* out, std::FILE* err) {
  char* buffer = nullptr;
  std::size_t capacity = 0;
  std::uint64_t line_number = 0;
  std::uint64_t printed = 0;
  std::uint64_t bad_lines = 0;
  ssize_t n = 0;
  while ((o.count == 0 || printed < o.count) && (n = ::getline(&buffer, &capacity, in)) >= 0) {
    ++line_number;
    const std::string_view text(buffer, static_cast<std::size_t>(n));
    if (text.find_first_not_of(" \t\r\n") == std::string_view::npos) continue;  // blank lines say nothing
    const Result<hal::CandumpLine> line = hal::parse_candump_line(text);
    if (!line) {
      ++bad_lines;
      std::string obj;
      json::StringSink sink(obj);
      json::Writer(sink).begin_object().member_uint64("line", line_number).member("error", line.error().message()).end_object();
      print_line(out, obj);
      continue;
    }
    if (o.node != 0 && !keep_for_node(line->frame, line->error_frame, o.node)) continue;
    print_line(out, describe_frame_json(line->unix_ns, line->interface_name(), line->frame, line->error_frame));
    ++printed;
  }
  const bool read_error = std::ferror(in) != 0;
  std::free(buffer);
  const char* name = o.source == "-" ? "standard input" : o.source.c_str();
  if (read_error) {
    std::fprintf(err, "sen3bot can dump: %s: read error after line %llu\n", name,
                 static_cast<unsigned long long>(line_number));
    return 1;
  }
  if (bad_lines > 0) {
    std::fprintf(err, "sen3bot can dump: %s: %llu bad line%s of %llu\n", name,
                 static_cast<unsigned long long>(bad_lines), bad_lines == 1 ? "" : "s",
                 static_cast<unsigned long long>(line_number));
    return 1;
  }
  return 0;
}

// A live bus until SIGINT/SIGTERM or --count frames. The time is the kernel's receive time
// when the backend has it, else when the frame was read (the wall clock). The backend reads
// the kernel's error frames itself; the link state changes they bring are printed as they come.
int dump_live(hal::CanBus& bus, const DumpOptions& o, std::FILE* out, std::FILE* err) {
  const StopOnSignal stop;
  hal::PosixClock clock;
  hal::CanLinkState link = bus.link_state();
  std::uint64_t printed = 0;
  const std::string interface(bus.name());
  while (StopOnSignal::requested() == 0 && (o.count == 0 || printed < o.count)) {
    if (bus.poll_fd() >= 0) {
      pollfd p{bus.poll_fd(), POLLIN, 0};
      (void)::poll(&p, 1, 100);  // wakes up to look at the stop flag
    } else {
      clock.sleep_until(clock.now() + hal::millis(10));
    }
    while (o.count == 0 || printed < o.count) {
      Result<std::optional<CanFrame>> r = bus.receive();
      if (!r) {
        std::fprintf(err, "sen3bot can dump: %s: %s\n", interface.c_str(), r.error().c_str());
        return 1;
      }
      if (!*r) break;
      const CanFrame& f = **r;
      if (o.node != 0 && !keep_for_node(f, false, o.node)) continue;
      const std::int64_t stamp = bus.last_receive_unix_ns();
      print_line(out, describe_frame_json(stamp >= 0 ? stamp : clock.unix_now_ns(), interface, f, false));
      ++printed;
    }
    if (const hal::CanLinkState now = bus.link_state(); now != link) {
      link = now;
      std::string obj;
      json::StringSink sink(obj);
      json::Writer w(sink);
      w.begin_object();
      member_time(w, clock.unix_now_ns());
      w.member("interface", interface).member("kind", "link").member("link", hal::to_string(now)).end_object();
      print_line(out, obj);
    }
    std::fflush(out);
  }
  return 0;
}

// A SocketCAN interface name: what is left when SOURCE is no file.
bool interface_like(std::string_view s) {
  if (s.empty() || s.size() > hal::CandumpLine::kMaxInterface) return false;
  for (const char c : s)
    if (c == '/' || c <= ' ' || c > '~') return false;
  return true;
}

bool parse_node(std::string_view text, unsigned& node) {
  std::uint32_t v = 0;
  if (!parse_u32(text, v) || !canopen::valid_node(v)) return false;
  node = v;
  return true;
}

}  // namespace

int can_dump_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  DumpOptions o;
  bool have_source = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--node" || arg == "--count") {
      if (i + 1 >= argc) {
        std::fprintf(err, "sen3bot can dump: %s needs a value\n%s", argv[i], kDumpUsage);
        return 2;
      }
      const std::string_view value = argv[++i];
      if (arg == "--node" && !parse_node(value, o.node)) {
        std::fprintf(err, "sen3bot can dump: --node '%s': a node id is 1..127\n", argv[i]);
        return 2;
      }
      if (arg == "--count" && (!parse_u64(value, o.count) || o.count == 0)) {
        std::fprintf(err, "sen3bot can dump: --count '%s': a positive number of frames\n", argv[i]);
        return 2;
      }
    } else if (arg.size() > 1 && arg.front() == '-') {
      std::fprintf(err, "sen3bot can dump: unknown option '%s'\n%s", argv[i], kDumpUsage);
      return 2;
    } else if (!have_source) {
      o.source = arg;
      have_source = true;
    } else {
      std::fprintf(err, "sen3bot can dump: one SOURCE only ('%s' is a second)\n%s", argv[i], kDumpUsage);
      return 2;
    }
  }
  if (!have_source) {
    std::fputs(kDumpUsage, err);
    return 2;
  }
  if (o.source == "-") return dump_log(stdin, o, out, err);
  struct stat st {};
  if (::stat(o.source.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) {
      std::fprintf(err, "sen3bot can dump: %s is a directory, not a candump log\n", o.source.c_str());
      return 1;
    }
    std::FILE* in = std::fopen(o.source.c_str(), "r");
    if (in == nullptr) {
      std::fprintf(err, "sen3bot can dump: %s: %s\n", o.source.c_str(), std::strerror(errno));
      return 1;
    }
    const int rc = dump_log(in, o, out, err);
    std::fclose(in);
    return rc;
  }
  const int stat_errno = errno;
  if (stat_errno != ENOENT || !interface_like(o.source)) {
    std::fprintf(err, "sen3bot can dump: %s: %s\n", o.source.c_str(), std::strerror(stat_errno));
    return 1;
  }
  Result<std::unique_ptr<hal::SocketCanBus>> bus = hal::SocketCanBus::open(o.source);
  if (!bus) {
    // Say both readings of SOURCE: a typo in a file name must not look like a CAN problem only.
    std::fprintf(err, "sen3bot can dump: %s: no such file, and as a CAN interface: %s\n", o.source.c_str(),
                 bus.error().c_str());
    return 1;
  }
  return dump_live(**bus, o, out, err);
}

// --- can io ---------------------------------------------------------------------------------

namespace {

// "OUT=V", OUT 1..8, V 0 or 1.
bool parse_set(std::string_view text, CanIoOptions& o) {
  const std::size_t eq = text.find('=');
  if (eq == std::string_view::npos) return false;
  std::uint32_t output = 0;
  const std::string_view value = text.substr(eq + 1);
  if (!parse_u32(text.substr(0, eq), output) || output < 1 || output > 8) return false;
  if (value != "0" && value != "1") return false;
  const auto bit = static_cast<std::uint8_t>(1u << (output - 1));
  o.set_mask = static_cast<std::uint8_t>(o.set_mask | bit);
  o.set_values = static_cast<std::uint8_t>(value == "1" ? (o.set_values | bit) : (o.set_values & ~bit));
  return true;
}

void write_events(json::Writer& w, const canopen::IoNodeMaster& m) {
  w.key("events").begin_object();
  for (std::size_t i = 0; i < canopen::kIoNodeEvents; ++i) {
    const auto e = static_cast<canopen::IoNodeEvent>(i);
    w.member_uint64(canopen::to_string(e), m.count(e));
  }
  w.end_object();
}

// The master's state and counters, for an error message.
std::string master_summary(const canopen::IoNodeMaster& m, bool heard, const hal::CanBus& bus, std::uint64_t sent,
                           std::uint64_t received) {
  std::string s;
  append(s, "master state %s, %s%s, link %s, %llu frames sent, %llu received;", canopen::to_string(m.state()),
         heard ? "last heartbeat state " : "no heartbeat heard", heard ? canopen::to_string(m.node_state()) : "",
         hal::to_string(bus.link_state()), static_cast<unsigned long long>(sent),
         static_cast<unsigned long long>(received));
  for (std::size_t i = 0; i < canopen::kIoNodeEvents; ++i) {
    const auto e = static_cast<canopen::IoNodeEvent>(i);
    append(s, " %s %llu", canopen::to_string(e), static_cast<unsigned long long>(m.count(e)));
  }
  if (m.count(canopen::IoNodeEvent::sdo_abort) > 0)
    append(s, "; last SDO abort 0x%08X at 0x%04X:%u (%s)", static_cast<unsigned>(m.last_abort()),
           static_cast<unsigned>(m.last_abort_at().index), static_cast<unsigned>(m.last_abort_at().sub),
           canopen::describe_abort(m.last_abort()));
  return s;
}

}  // namespace

void write_can_bits(json::Writer& w, std::string_view key, std::uint8_t bits) { write_bits(w, key, bits); }

int parse_can_io(int argc, char** argv, const char* program, const char* usage, CanIoOptions& o, std::FILE* err) {
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "%s can io: %s needs a value\n%s", program, argv[i], usage);
      return 2;
    }
    const std::string_view value = argv[++i];
    bool ok = true;
    if (arg == "--iface") {
      o.iface = value;
      ok = value == "sim" || interface_like(value);
    } else if (arg == "--node") {
      ok = parse_node(value, o.node);
    } else if (arg == "--set") {
      ok = parse_set(value, o);
    } else if (arg == "--timeout") {
      ok = parse_double(value, o.timeout_s) && o.timeout_s > 0 && o.timeout_s <= 3600;
    } else {
      std::fprintf(err, "%s can io: unknown option '%s'\n%s", program, argv[i - 1], usage);
      return 2;
    }
    if (!ok) {
      std::fprintf(err, "%s can io: bad value '%s' for %s\n%s", program, argv[i], argv[i - 1], usage);
      return 2;
    }
  }
  if (o.iface.empty() || o.node == 0) {
    std::fprintf(err, "%s can io: --iface and --node are required\n%s", program, usage);
    return 2;
  }
  canopen::IoNodeConfig config;
  config.node = static_cast<std::uint8_t>(o.node);
  if (Status s = canopen::IoNodeMaster::check(config); !s) {
    std::fprintf(err, "%s can io: %s\n", program, s.error().c_str());
    return 2;
  }
  return 0;
}

int run_can_io(const CanIoOptions& o, hal::CanBus& bus, CanIoPeer* peer, const char* program, std::FILE* out,
               std::FILE* err) {
  canopen::IoNodeConfig config;
  config.node = static_cast<std::uint8_t>(o.node);
  hal::PosixClock clock;
  const StopOnSignal stop;
  canopen::IoNodeMaster master(config);
  constexpr hal::Nanos kCycle = hal::millis(10);
  const hal::Nanos start = clock.now();
  const hal::Nanos deadline = start + static_cast<hal::Nanos>(o.timeout_s * 1e9);
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  bool heard = false;  // a heartbeat or boot-up from the node
  hal::Nanos operational_ns = -1;
  bool outputs_applied = false;
  std::optional<std::uint8_t> outputs_sent;  // the last RPDO1 that went to the bus

  const auto fail = [&](const char* what) {
    std::fprintf(err, "%s can io: node %u on %s %s after %.1f s: %s\n", program, o.node, o.iface.c_str(), what,
                 hal::to_seconds(clock.now() - start), master_summary(master, heard, bus, sent, received).c_str());
    return 1;
  };
  const auto transmit = [&](const CanFrame& f) -> Status {
    if (Status s = bus.send(f); !s) return s;
    ++sent;
    const Classified c = canopen::classify(f);
    if (c.kind == Kind::rpdo && c.pdo == 1 && f.dlc >= 1) outputs_sent = f.data[0];
    return {};
  };

  hal::Nanos next = start;
  for (;;) {
    const hal::Nanos now = clock.now();
    // What the bus brought, then the master's timers and frames.
    for (;;) {
      Result<std::optional<CanFrame>> r = bus.receive();
      if (!r) {
        std::fprintf(err, "%s can io: %s: %s\n", program, o.iface.c_str(), r.error().c_str());
        return 1;
      }
      if (!*r) break;
      ++received;
      const Classified c = canopen::classify(**r);
      heard = heard || (c.kind == Kind::heartbeat && c.node == o.node);
      master.on_frame(**r, now);
    }
    std::array<CanFrame, 4> frames{};
    const std::size_t n = master.poll(now, frames);
    for (std::size_t i = 0; i < n; ++i) {
      // A full transmit queue or a bus-off drops the frame: the master sends again (SDO
      // retries, NMT start repeated, outputs refreshed), and the timeout's report says why.
      if (Status s = transmit(frames[i]); !s && s.error().code() != Errc::would_block &&
                                              s.error().code() != Errc::disconnected) {
        std::fprintf(err, "%s can io: %s: %s\n", program, o.iface.c_str(), s.error().c_str());
        return 1;
      }
    }
    (void)bus.flush();  // what the backend queued goes out as soon as there is room
    if (peer != nullptr) peer->step(now);

    if (operational_ns < 0 && master.state() == canopen::IoNodeState::operational) operational_ns = now;
    // The outputs are set once the inputs are there (the node is fully up), and the command
    // is done when an RPDO1 carrying them went out.
    if (!outputs_applied && master.inputs_valid()) {
      master.set_outputs(static_cast<std::uint8_t>((master.outputs() & ~o.set_mask) | o.set_values));
      outputs_applied = true;
    } else if (outputs_applied && outputs_sent == master.outputs()) {
      break;
    }
    if (StopOnSignal::requested() != 0) return fail("interrupted");
    if (now >= deadline) {
      if (master.state() != canopen::IoNodeState::operational) return fail("not operational");
      if (!master.inputs_valid()) return fail("operational but no inputs (TPDO1) came");
      return fail("outputs not sent");
    }
    next += kCycle;
    clock.sleep_until(next);
  }

  std::string line;
  json::StringSink sink(line);
  json::Writer w(sink);
  w.begin_object()
      .member("iface", o.iface)
      .member_uint32("node", o.node)
      .member("state", canopen::to_string(master.state()))
      .member("heartbeat", canopen::to_string(master.node_state()))
      .member_bool("inputs_valid", master.inputs_valid());
  write_bits(w, "inputs", master.inputs());
  write_bits(w, "outputs", master.outputs());
  w.member("link", hal::to_string(bus.link_state()))
      .key("operational_s").fixed_or_null(hal::to_seconds(operational_ns - start), 3)
      .member_uint64("frames_sent", sent)
      .member_uint64("frames_received", received);
  write_events(w, master);
  if (master.count(canopen::IoNodeEvent::emergency) + master.count(canopen::IoNodeEvent::emergency_reset) > 0) {
    const canopen::Emergency& e = master.last_emergency();
    w.key("last_emergency")
        .begin_object()
        .member("code", printed("0x%04X", static_cast<unsigned>(e.code)))
        .member("register", printed("0x%02X", static_cast<unsigned>(e.error_register)))
        .member("description", canopen::describe_emergency(e.code))
        .end_object();
  }
  if (peer != nullptr) peer->write_json(w);
  w.end_object();
  print_line(out, line);
  return 0;
}

int can_io_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  CanIoOptions o;
  if (int rc = parse_can_io(argc, argv, "sen3bot", kIoUsage, o, err); rc != 0) return rc;
  if (o.iface == "sim") {
    std::fprintf(err, "sen3bot can io: --iface sim: the emulated node is in the simulator: sen3bot-sim can io "
                      "--iface sim\n");
    return 2;
  }
  Result<std::unique_ptr<hal::SocketCanBus>> bus = hal::SocketCanBus::open(o.iface);
  if (!bus) {
    std::fprintf(err, "sen3bot can io: %s\n", bus.error().c_str());
    return 1;
  }
  return run_can_io(o, **bus, nullptr, "sen3bot", out, err);
}

}  // namespace sen3bot::firmware
