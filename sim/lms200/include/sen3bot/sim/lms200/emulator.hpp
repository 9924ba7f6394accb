#pragma once
// The scanner side of an LMS200 link, wire-exact: standalone ACK before each command reply
// (none before streamed B0), status byte 0x10 by default, baud changes answered at the old
// rate and then applied, output paced at 10 bits per byte of the current rate and at the
// mirror's scan rate (the newest complete scan goes out when the line is slower), ranges from
// a RangeSource, and fault injection. Streams complete scans (20 24, B0), partial scans
// (20 2A, B0), mean values (20 26, B6) and sub-ranges (20 27, B7).
//
// The core is step(now) over a hal::ByteStream: in lockstep the pacing follows the simulated
// clock. Lms200PtyRunner (pty_runner.hpp) runs it in real time on a pseudo-terminal.
#include <array>
#include <cstdint>
#include <mutex>
#include <span>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {

// The beams of one scan in the sensor frame: beam i points at angle_min_rad + i * increment
// (0 rad = straight ahead, counter-clockwise positive).
struct ScanGeometry {
  double angle_min_rad = 0;
  double angle_increment_rad = 0;
  std::size_t count = 0;
  double range_max_m = 0;  // beyond this the scanner reports "value > maximum"
};

struct SensorPose {
  double x_m = 0;
  double y_m = 0;
  double theta_rad = 0;
};

// What the emulated scanner sees. ranges() fills out_m (size == geometry.count) with the
// distance along each beam in metres; +infinity where nothing is hit. It runs inside the
// emulator's step() and must not allocate.
class RangeSource {
 public:
  RangeSource() = default;
  RangeSource(const RangeSource& other) noexcept : pose_(other.sensor_pose()) {}
  RangeSource& operator=(const RangeSource& other) noexcept {
    if (this != &other) {
      const SensorPose p = other.sensor_pose();
      set_sensor_pose(p.x_m, p.y_m, p.theta_rad);
    }
    return *this;
  }
  virtual ~RangeSource() = default;
  virtual void ranges(hal::Nanos t, const ScanGeometry& geometry, std::span<float> out_m) = 0;

  // The sensor's pose in the world frame; set from another thread (a simulated robot).
  void set_sensor_pose(double x_m, double y_m, double theta_rad) noexcept {
    std::lock_guard lock(pose_mutex_);
    pose_ = {x_m, y_m, theta_rad};
  }
  [[nodiscard]] SensorPose sensor_pose() const noexcept {
    std::lock_guard lock(pose_mutex_);
    return pose_;
  }

 private:
  mutable std::mutex pose_mutex_;
  SensorPose pose_;
};

// A world of wall segments (at most kMaxSegments): exact, cheap ranges for tests.
class WallWorld final : public RangeSource {
 public:
  static constexpr std::size_t kMaxSegments = 64;
  struct Segment {
    double x0_m, y0_m, x1_m, y1_m;
  };

  bool add_segment(Segment s) noexcept;
  // Axis-aligned rectangle outline (a room seen from inside, a box from outside).
  bool add_rectangle(double min_x_m, double min_y_m, double max_x_m, double max_y_m) noexcept;
  // A width x depth room with its corner at the origin and a box of side box_m whose centre is
  // at (box_x_m, box_y_m); the sensor starts at the room's centre, facing +x.
  static WallWorld room_with_box(double width_m, double depth_m, double box_x_m, double box_y_m, double box_m);

  // Distance from (x, y) along heading angle_rad to the nearest wall; +inf if none.
  [[nodiscard]] double cast(double x_m, double y_m, double angle_rad) const noexcept;
  void ranges(hal::Nanos t, const ScanGeometry& geometry, std::span<float> out_m) override;
  [[nodiscard]] std::size_t segment_count() const noexcept { return count_; }

 private:
  std::array<Segment, kMaxSegments> segments_{};
  std::size_t count_ = 0;
};

// The client's side of the line: the rate its serial port is set to.
class ClientLine {
 public:
  virtual ~ClientLine() = default;
  virtual Result<std::uint32_t> client_baud() = 0;
};

// A line for lockstep simulation: the driver switches its rate through LineControl, the
// emulator reads it through ClientLine.
class SimulatedLine final : public LineControl, public ClientLine {
 public:
  explicit SimulatedLine(std::uint32_t baud = 9600) noexcept : baud_(baud) {}
  Status set_baud(std::uint32_t baud) override {
    baud_ = baud;
    ++changes_;
    return Status::success();
  }
  Result<std::uint32_t> client_baud() override { return baud_; }
  [[nodiscard]] std::uint32_t baud() const noexcept { return baud_; }
  [[nodiscard]] int changes() const noexcept { return changes_; }

 private:
  std::uint32_t baud_;
  int changes_ = 0;
};

// Injected faults; "every N" counts streamed scans, 0 = never.
struct FaultPlan {
  std::uint32_t corrupt_crc_every = 0;     // wrong CRC
  std::uint32_t truncate_every = 0;        // only the first half of the telegram
  std::uint32_t false_header_every = 0;    // "02 80" with a plausible LEN in front of the telegram
  std::uint32_t invalid_values_every = 0;  // every 10th value replaced by an error code (>= 8183)
  std::uint32_t dazzle_every = 0;          // dazzle flag on every 10th value
  std::uint32_t oversize_len_every = 0;    // "02 80" with LEN 822 (> 814) in front of the telegram
  bool silent = false;                     // sends nothing and ignores requests (cable pulled)
  bool suppress_ack = false;               // no 0x06 before replies
  bool device_fault = false;               // B1 device status "fault", status byte level "error"
};

struct EmulatorOptions {
  std::uint8_t status = kStatusNormal;           // status byte of every reply; level error or
                                                 // fatal (bits 0-2) also faults the B1 device status
  std::uint32_t initial_baud = 9600;             // power-on rate ("permanent" rate if not 9600)
  Variant variant{180, 100};
  Units units = Units::cm;
  MeasuringMode measuring_mode = MeasuringMode::range8_fields_dazzle;
  std::uint8_t availability = 0;                 // 0x02: real-time indices in B0
  bool short_config = false;                     // 32-byte F4 (older LMS200 firmware)
  std::uint8_t address = 0;
  std::int64_t config_write_delay_ms = 20;       // EEPROM write time before F7
  FaultPlan faults;
};

struct EmulatorCounters {
  std::uint64_t requests = 0;
  std::uint64_t naks_sent = 0;
  std::uint64_t rejected = 0;        // 0x92 sent
  std::uint64_t scans_sent = 0;
  std::uint64_t scans_skipped = 0;   // completed while the line was busy
  std::uint64_t config_writes = 0;   // 0x77 accepted
  std::uint64_t baud_changes = 0;
  std::uint64_t garbled_rx_bytes = 0;  // arrived while the client's rate differed
  std::uint64_t garbled_tx_bytes = 0;
  std::uint64_t bytes_sent = 0;
  // The first kLoggedRequests requests as (command << 8) | first parameter byte.
  static constexpr std::size_t kLoggedRequests = 64;
  std::array<std::uint16_t, kLoggedRequests> request_log{};
};

class Lms200Emulator {
 public:
  // `client` may be null (no baud check, e.g. a replay harness).
  Lms200Emulator(const EmulatorOptions& options, hal::ByteStream& stream, RangeSource& world,
                 ClientLine* client = nullptr) noexcept;

  void step(hal::Nanos now) noexcept;

  // Takes effect at the next step.
  void set_faults(const FaultPlan& faults) noexcept { options_.faults = faults; }
  void set_status_byte(std::uint8_t status) noexcept { options_.status = status; }
  // Power cycle: back to the power-on rate and monitoring mode, queues emptied.
  void power_cycle(hal::Nanos now) noexcept;

  [[nodiscard]] std::uint32_t baud() const noexcept { return baud_; }
  [[nodiscard]] Variant variant() const noexcept { return variant_; }
  [[nodiscard]] Units units() const noexcept { return static_cast<Units>(config_[config_offset::kUnits]); }
  [[nodiscard]] MeasuringMode measuring_mode() const noexcept {
    return static_cast<MeasuringMode>(config_[config_offset::kMeasuringMode]);
  }
  [[nodiscard]] bool streaming() const noexcept {
    return mode_ == OperatingMode::continuous_all || mode_ == OperatingMode::partial_scans ||
           mode_ == OperatingMode::mean_values || mode_ == OperatingMode::subrange;
  }
  // What the scanner reports now: the status byte S of every telegram, and the B1 device
  // status. A fault (FaultPlan::device_fault, or an S whose level is error or fatal) shows in both.
  [[nodiscard]] std::uint8_t status_byte() const noexcept;
  [[nodiscard]] std::uint8_t device_status() const noexcept;
  [[nodiscard]] OperatingMode mode() const noexcept { return mode_; }
  [[nodiscard]] const EmulatorCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const ParserStats& parser_stats() const noexcept { return parser_.stats(); }
  [[nodiscard]] ScanGeometry geometry() const noexcept;
  // The raw words the emulator would send for a scan taken at time t (for test oracles).
  std::size_t scan_words(hal::Nanos t, std::span<std::uint16_t> out) noexcept;

 private:
  static constexpr std::size_t kQueueBytes = 4096;

  // The words of one scan at time t: the complete scan, or one mirror turn's 1 deg raster at
  // the current partial offset.
  std::size_t fill_words(hal::Nanos t, std::span<std::uint16_t> out, bool partial_raster) noexcept;
  void handle(hal::Nanos now, FrameView request) noexcept;
  void reply(std::uint8_t code, std::span<const std::uint8_t> data, bool ack = true) noexcept;
  bool enqueue(std::span<const std::uint8_t> bytes) noexcept;
  // `streamed`: part of the current streaming mode (B0, B6 or B7 by mode, counted for skips);
  // otherwise one B0 on request (30 01).
  void enqueue_scan(hal::Nanos now, std::int64_t scan_number, bool streamed) noexcept;
  void start_stream(hal::Nanos now, OperatingMode mode) noexcept;
  // Scans streaming counts in: a mirror turn for partial scans, a complete scan otherwise.
  [[nodiscard]] hal::Nanos stream_period_ns() const noexcept;
  void restart_mean() noexcept;  // a new mean starts with no scans taken
  void accumulate_mean(hal::Nanos now) noexcept;
  void pace_output(hal::Nanos now, bool garble) noexcept;
  [[nodiscard]] std::size_t queued() const noexcept { return static_cast<std::size_t>(q_tail_ - q_head_); }

  EmulatorOptions options_;
  hal::ByteStream& stream_;
  RangeSource& world_;
  ClientLine* client_;
  TelegramParser parser_;

  std::uint32_t baud_;
  std::uint32_t pending_baud_ = 0;   // applied once the A0 reply has left the line
  OperatingMode mode_ = OperatingMode::monitoring;
  bool installation_ = false;
  Variant variant_;
  std::array<std::uint8_t, kConfigBytes> config_{};
  hal::Nanos config_reply_at_ns_ = -1;  // a delayed F7 waiting for the EEPROM
  std::array<std::uint8_t, kConfigBytes + 1> config_reply_{};
  std::size_t config_reply_size_ = 0;

  std::array<std::uint8_t, kQueueBytes> queue_{};
  std::uint64_t q_head_ = 0;
  std::uint64_t q_tail_ = 0;
  hal::Nanos now_ = 0;            // time of the current step
  hal::Nanos line_free_ns_ = 0;   // when the byte being sent has left the line
  std::int64_t last_scan_sent_ = -1;
  std::uint8_t partial_offset_ = 0;
  std::uint32_t telegram_index_ = 0;
  // Mode 0x26: sums over the current block of mean_samples_ scans, and the last finished mean.
  std::uint8_t mean_samples_ = 0;
  std::uint8_t mean_taken_ = 0;
  std::int64_t mean_blocks_ = 0;        // means finished since the mode started
  std::int64_t last_scan_taken_ = -1;   // newest scan added to the sums
  std::array<std::uint32_t, kMaxValues> mean_sum_{};
  std::array<std::uint8_t, kMaxValues> mean_valid_{};
  std::array<std::uint16_t, kMaxValues> mean_code_{};
  std::array<std::uint16_t, kMaxValues> mean_words_{};
  // Mode 0x27: 1-based first and last value.
  std::uint16_t subrange_first_ = 1;
  std::uint16_t subrange_last_ = 1;

  std::array<float, kMaxValues> ranges_m_{};
  std::array<std::uint16_t, kMaxValues> words_{};
  std::array<std::uint8_t, kMaxFrameBytes + 8> frame_{};
  EmulatorCounters counters_;
};

}  // namespace sen3bot::lms200
