#pragma once
// The LMS200 device state machine: non-blocking and driven by time. step(now) reads what the
// link has, advances the start-up sequence or decodes scans, and sends the next request. It
// never sleeps, so the same code runs on the monotonic clock and in lockstep simulation.
//
// Start-up: probe the baud rate with 20 25 (configured rate first, then 9600, 19200, 38400,
// 500000) -> 20 4x at the old rate, switch the host, settle -> 31 (verify the baud, read the
// variant) -> 3B in monitoring mode if the variant differs -> 74 -> only if units or measuring
// mode differ: 20 00 password, 77, 20 25 (the EEPROM wears; 0x66 is never sent) -> 20 24.
// Streaming: B0 telegrams become LaserScans; no scan for stale_scan_periods expected intervals
// is an error, and every error restarts the sequence after restart_delay_ms.
#include <cstdint>
#include <string>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"
#include "sen3bot/lms200/scan.hpp"

namespace sen3bot::lms200 {

// Everything the driver can be told. Defaults suit an LMS200 at address 0 on RS-422.
struct Lms200Config {
  std::string port = "/dev/ttyUSB0";   // serial device or "tcp://host:port" (hal::open_byte_stream)
  std::uint32_t baud = 500000;         // target rate: 9600, 19200, 38400 or 500000
  Variant variant{180, 50};            // scan angle (deg) and resolution (1/100 deg)
  Units units = Units::mm;             // cm: 81.82 m range, 1 cm steps; mm: 8.182 m, 1 mm steps
  MeasuringMode measuring_mode = MeasuringMode::range8_fields_dazzle;
  std::uint8_t lms_address = 0;        // replies come from 0x80 | address
  std::string password = "SICK_LMS";   // installation mode, only used when the config differs
  bool probe_bauds = true;             // false: only ever talk at `baud`
  std::int64_t probe_timeout_ms = 300;  // per try, plus one maximum telegram at that rate
  std::int64_t reply_timeout_ms = 3000;  // mode changes may take 3 s
  std::int64_t config_write_timeout_ms = 15000;  // EEPROM write behind 0x77
  std::int64_t inter_byte_timeout_ms = 35;   // gap that abandons a partial telegram
  std::int64_t baud_settle_ms = 100;         // after switching the host's rate
  std::int64_t nak_retry_delay_ms = 30;      // the LMS wants >= 30 ms before a resend
  int max_tries = 3;                         // per request (1 = no retry)
  int stale_scan_periods = 3;                // no scan for this many expected intervals -> error
  std::int64_t restart_delay_ms = 500;       // after an error, before probing again
  bool stop_to_9600 = true;                  // clean stop leaves the LMS at its power-on rate
                                             // (only when the host's rate can follow)
};

// Changes the host side's baud rate (SerialPort::set_baud, or a simulated line).
using LineControl = hal::BaudControl;

// The time between two streamed scans: the telegram's transmission at `baud`, or the mirror's
// period for the variant when the line is faster.
[[nodiscard]] hal::Nanos scan_interval_ns(Variant variant, std::uint32_t baud) noexcept;

struct DeviceCounters {
  std::uint64_t scans = 0;
  std::uint64_t restarts = 0;       // times the start-up sequence began again after an error
  std::uint64_t errors = 0;
  std::uint64_t stale_events = 0;
  std::uint64_t timeouts = 0;       // requests that got no reply in time (each try)
  std::uint64_t naks = 0;
  std::uint64_t missing_acks = 0;   // replies that came without the 0x06 before them
  std::uint64_t rejected = 0;       // 0x92 replies
  std::uint64_t config_writes = 0;  // 0x77 sent (EEPROM writes)
  std::uint64_t bad_scans = 0;      // CRC-valid B0 that did not decode
  std::uint64_t ignored_frames = 0;  // valid telegrams nobody asked for
  std::uint64_t fault_reports = 0;   // B1 replies with a device status other than OK
};

// Transmission time of `bytes` at `baud`, 8N1 = 10 bits per byte.
constexpr hal::Nanos transmission_ns(std::size_t bytes, std::uint32_t baud) {
  return baud == 0 ? 0 : static_cast<hal::Nanos>(bytes) * 10 * hal::kNanosPerSecond / baud;
}

class Lms200Device {
 public:
  enum class Phase : std::uint8_t {
    idle, probe, set_baud, settle, verify_status, set_variant, read_config, enter_installation,
    write_config, leave_installation, start_stream, streaming, error_wait,
    stop_monitoring, stop_baud, stopped,
  };

  // `line` may be null: then the driver talks only at config.baud.
  Lms200Device(const Lms200Config& config, hal::ByteStream& stream, LineControl* line) noexcept;

  // Begins (or restarts) the start-up sequence.
  void start(hal::Nanos now) noexcept;
  // Advances everything; call often (every ms or so in real time, every step in lockstep).
  void step(hal::Nanos now) noexcept;
  // Clean stop: 20 25, then (optionally) 20 42 and the host back to 9600. Keep calling step()
  // until phase() is stopped.
  void request_stop(hal::Nanos now) noexcept;

  [[nodiscard]] Phase phase() const noexcept { return phase_; }
  [[nodiscard]] LinkState link_state() const noexcept;
  [[nodiscard]] std::uint32_t baud() const noexcept { return baud_; }
  [[nodiscard]] const Error& last_error() const noexcept { return last_error_; }
  [[nodiscard]] bool has_error() const noexcept { return error_count_ > 0; }
  [[nodiscard]] const DeviceCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const ParserStats& parser_stats() const noexcept { return parser_.stats(); }
  [[nodiscard]] const StatusReply& status() const noexcept { return status_; }
  // The scanner reports a fault: B1 device status at start-up, or the level bits of the
  // newest telegram's status byte (error or fatal). Scans keep flowing; the user decides.
  [[nodiscard]] bool scanner_fault() const noexcept;
  [[nodiscard]] const ConfigBlock& config_block() const noexcept { return config_block_; }

  // The newest scan; `sequence` grows with each one. take_new_scan() copies it out once.
  [[nodiscard]] const LaserScan& latest_scan() const noexcept { return scan_; }
  bool take_new_scan(LaserScan& out) noexcept;
  // Expected interval between scans at the current baud and variant.
  [[nodiscard]] hal::Nanos expected_scan_interval_ns() const noexcept;
  [[nodiscard]] const char* phase_name() const noexcept;

  // Replaces the stream (after the owner reopened a vanished device).
  void set_stream(hal::ByteStream& stream) noexcept { stream_ = &stream; }

 private:
  void fail(hal::Nanos now, const Error& error) noexcept;
  void send(hal::Nanos now, const Request& request, std::uint8_t reply, hal::Nanos timeout_ns) noexcept;
  void resend(hal::Nanos now) noexcept;
  void flush_tx() noexcept;
  void enter(hal::Nanos now, Phase phase) noexcept;
  void on_frame(hal::Nanos now, FrameView frame) noexcept;
  void on_reply(hal::Nanos now, FrameView frame) noexcept;
  void on_timeout(hal::Nanos now) noexcept;
  void on_scan(hal::Nanos now, FrameView frame) noexcept;
  bool switch_host_baud(hal::Nanos now, std::uint32_t baud) noexcept;
  hal::Nanos probe_timeout_ns(std::uint32_t baud) const noexcept;

  // What the state machine keeps of Lms200Config: the same fields without strings, so the
  // device is trivially destructible and may sit in an arena released without destructors.
  struct Settings {
    std::uint32_t baud;
    Variant variant;
    Units units;
    MeasuringMode measuring_mode;
    std::uint8_t lms_address;
    std::array<char, kPasswordBytes> password;
    bool probe_bauds;
    std::int64_t probe_timeout_ms;
    std::int64_t reply_timeout_ms;
    std::int64_t config_write_timeout_ms;
    std::int64_t inter_byte_timeout_ms;
    std::int64_t baud_settle_ms;
    std::int64_t nak_retry_delay_ms;
    int max_tries;
    int stale_scan_periods;
    std::int64_t restart_delay_ms;
    bool stop_to_9600;
  };
  static Settings settings_of(const Lms200Config& c) noexcept;

  Settings config_;
  hal::ByteStream* stream_;
  LineControl* line_;
  TelegramParser parser_;

  Phase phase_ = Phase::idle;
  std::uint32_t baud_ = 0;
  std::array<std::uint32_t, 5> probe_bauds_{};
  std::size_t probe_count_ = 0;
  std::size_t probe_index_ = 0;

  // The one outstanding request (all commands are serialised).
  Request pending_;
  std::size_t pending_written_ = 0;
  bool awaiting_ = false;
  bool got_ack_ = false;
  std::uint8_t expected_reply_ = 0;
  int tries_ = 0;
  hal::Nanos timeout_ns_ = 0;
  hal::Nanos deadline_ns_ = 0;
  hal::Nanos resend_at_ns_ = -1;
  hal::Nanos phase_until_ns_ = 0;   // settle / error_wait end
  hal::Nanos last_rx_ns_ = 0;
  hal::Nanos last_scan_ns_ = 0;
  bool stop_requested_ = false;

  StatusReply status_;
  std::uint8_t last_status_byte_ = kStatusNormal;  // of the newest reply or scan
  ConfigBlock config_block_;
  ScanTelegram telegram_;
  LaserScan scan_;
  std::uint64_t taken_sequence_ = 0;
  DeviceCounters counters_;
  std::uint64_t error_count_ = 0;
  Error last_error_;
};

}  // namespace sen3bot::lms200
