#include "session.hpp"

#include "rig.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/capture/writer.hpp"

namespace sen3bot::lms200::testing {

namespace {

// Switches the simulated line and marks the switch in the capture.
class RecordedLine final : public LineControl {
 public:
  RecordedLine(SimulatedLine& line, capture::RecordingStream& recorder) : line_(line), recorder_(recorder) {}
  Status set_baud(std::uint32_t baud) override {
    Status s = line_.set_baud(baud);
    recorder_.note_baud_change(baud);
    return s;
  }

 private:
  SimulatedLine& line_;
  capture::RecordingStream& recorder_;
};

}  // namespace

Lms200Config session_driver_config() {
  Lms200Config c;
  c.baud = 38400;
  c.variant = {180, 50};
  c.units = Units::mm;
  return c;
}

Status record_session(const std::filesystem::path& path) {
  hal::SimClock clock;
  capture::CaptureWriter writer(1 << 20);
  capture::CaptureInfo info;
  info.start_monotonic_ns = clock.now();
  info.channels.push_back({kSessionChannel, "lms200", 9600});
  if (Status s = writer.open(path, info); !s) return s;

  hal::MemoryPipe pipe(16384);
  WallWorld world = test_world();
  SimulatedLine line(9600);
  Lms200Emulator emulator(EmulatorOptions{}, pipe.b(), world, &line);
  capture::RecordingStream recorder(pipe.a(), writer, kSessionChannel, clock);
  RecordedLine recorded_line(line, recorder);
  Lms200Device device(session_driver_config(), recorder, &recorded_line);

  hal::Nanos now = 0;
  auto step = [&] {
    clock.advance_to(now);
    emulator.step(now);
    device.step(now);
    now += kSessionStepNs;
  };
  device.start(now);
  while (device.counters().scans < 4 && now < hal::seconds(10)) step();
  FaultPlan faults;
  faults.corrupt_crc_every = 3;
  faults.false_header_every = 4;
  faults.invalid_values_every = 2;
  emulator.set_faults(faults);
  while (device.counters().scans < 8 && now < hal::seconds(15)) step();
  emulator.set_faults({});
  device.request_stop(now);
  while (device.phase() != Lms200Device::Phase::stopped && now < hal::seconds(20)) step();
  for (int i = 0; i < 10; ++i) step();
  if (device.phase() != Lms200Device::Phase::stopped)
    return Error::format(Errc::timeout, "session did not stop: %s", device.last_error().c_str());
  return writer.close();
}

}  // namespace sen3bot::lms200::testing
