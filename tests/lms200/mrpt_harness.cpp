// Runs MRPT's CSickLaserSerial, an LMS200 client we did not write, against our emulator on a
// pseudo-terminal, and checks the scans it decodes against the emulator's world.
//
// usage: lms200_mrpt_harness --baud B --units cm|mm --fov 100|180 --res 25|50|100
//                            [--scans N] [--start-baud B] [--lms-units cm|mm] [--timeout S]
// exit status: 0 all scans matched, 1 mismatch or timeout, 2 bad arguments.
#include <mrpt/hwdrivers/CSickLaserSerial.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <algorithm>

#include "rig.hpp"
#include "sen3bot/sim/lms200/pty_runner.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::lms200;

struct Args {
  std::uint32_t baud = 38400;
  std::uint32_t start_baud = 9600;
  bool mm = false;
  bool lms_mm = false;  // the emulated scanner's configured units at power-on
  int fov_deg = 180;
  int res_cdeg = 50;
  int scans = 3;
  double timeout_s = 60;
};

bool parse(int argc, char** argv, Args& a) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const char* v = argv[i + 1];
    if (k == "--baud") a.baud = static_cast<std::uint32_t>(std::atol(v));
    else if (k == "--start-baud") a.start_baud = static_cast<std::uint32_t>(std::atol(v));
    else if (k == "--units") a.mm = std::strcmp(v, "mm") == 0;
    else if (k == "--lms-units") a.lms_mm = std::strcmp(v, "mm") == 0;
    else if (k == "--fov") a.fov_deg = std::atoi(v);
    else if (k == "--res") a.res_cdeg = std::atoi(v);
    else if (k == "--scans") a.scans = std::atoi(v);
    else if (k == "--timeout") a.timeout_s = std::atof(v);
    else return false;
  }
  return (argc % 2) == 1;
}

void print_requests(Lms200PtyRunner& runner) {
  runner.with_emulator([](Lms200Emulator& e) {
    std::printf("requests:");
    for (std::size_t i = 0; i < std::min<std::size_t>(e.counters().requests, EmulatorCounters::kLoggedRequests); ++i)
      std::printf(" %02x%02x", e.counters().request_log[i] >> 8, e.counters().request_log[i] & 0xFF);
    std::printf("\n");
  });
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (!parse(argc, argv, a)) {
    std::fprintf(stderr, "usage: %s --baud B --units cm|mm --fov F --res R [--scans N] [--start-baud B]\n", argv[0]);
    return 2;
  }
  WallWorld world = testing::test_world();
  EmulatorOptions eo;
  eo.initial_baud = a.start_baud;
  if (a.lms_mm) {
    eo.units = Units::mm;
    eo.measuring_mode = MeasuringMode::range32_field_a;  // what MRPT selects for mm
  }
  Result<std::unique_ptr<Lms200PtyRunner>> runner = Lms200PtyRunner::open(eo, world);
  if (!runner) {
    std::fprintf(stderr, "harness: %s\n", runner.error().c_str());
    return 1;
  }
  (*runner)->start();

  // initialize() opens the port and runs MRPT's start-up sequence. It throws when that fails
  // (its ACK timeouts are tight for a loaded machine); a retry is a fresh client against a
  // power-cycled scanner, as a user would do.
  std::unique_ptr<mrpt::hwdrivers::CSickLaserSerial> laser;
  for (int attempt = 1;; ++attempt) {
    laser = std::make_unique<mrpt::hwdrivers::CSickLaserSerial>();
    laser->setSerialPort(std::string((*runner)->slave_path()));
    laser->setBaudRate(static_cast<int>(a.baud));
    laser->setMillimeterMode(a.mm);
    laser->setScanFOV(a.fov_deg);
    laser->setScanResolution(a.res_cdeg);
    try {
      laser->initialize();
      break;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "harness: initialize() attempt %d threw: %s\n", attempt, e.what());
      print_requests(**runner);
      if (attempt == 3) return 1;
      laser.reset();
      (*runner)->with_emulator([](Lms200Emulator& emulator) { emulator.power_cycle(hal::PosixClock().now()); });
    }
  }

  const std::size_t expected_count = static_cast<std::size_t>(a.fov_deg * 100 / a.res_cdeg + 1);
  const double unit_m = a.mm ? 0.001 : 0.01;
  const auto start = std::chrono::steady_clock::now();
  int good = 0;
  int hardware_errors = 0;
  int failures = 0;
  int exceptions = 0;
  while (good < a.scans) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > a.timeout_s) {
      std::fprintf(stderr, "harness: timeout after %d good scans (%d hardware errors)\n", good, hardware_errors);
      return 1;
    }
    bool have = false;
    bool hardware_error = false;
    mrpt::obs::CObservation2DRangeScan obs;
    try {
      laser->doProcessSimple(have, obs, hardware_error);
    } catch (const std::exception& e) {
      // MRPT throws when one round of tryToOpenComms fails; its next call tries again, which
      // is how its own grabber loop uses it.
      std::fprintf(stderr, "harness: MRPT threw: %s\n", e.what());
      if (++exceptions > 3) return 1;
      continue;
    }
    if (hardware_error) {
      ++hardware_errors;
      continue;
    }
    if (!have) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    if (obs.getScanSize() != expected_count) {
      std::fprintf(stderr, "harness: scan of %zu values, expected %zu\n", obs.getScanSize(), expected_count);
      return 1;
    }
    // Beam i of MRPT's scan. MRPT 2.5 reports an aperture of pi whatever the FOV, so the
    // angles come from the FOV we asked for.
    const double fov_rad = a.fov_deg * M_PI / 180.0;
    const SensorPose p = world.sensor_pose();
    const double step = fov_rad / static_cast<double>(expected_count - 1);
    int compared = 0;
    for (std::size_t i = 0; i < expected_count; ++i) {
      const std::size_t beam = obs.rightToLeft ? i : expected_count - 1 - i;
      const double angle = -fov_rad / 2.0 + static_cast<double>(beam) * step;
      const double r = world.cast(p.x_m, p.y_m, p.theta_rad + angle);
      const double want = std::round(r / unit_m) * unit_m;
      if (!std::isfinite(r) || std::round(r / unit_m) >= 8183) continue;
      if (!obs.getScanRangeValidity(i) || std::abs(obs.getScanRange(i) - want) > 1e-4) {
        if (++failures <= 5)
          std::fprintf(stderr, "harness: beam %zu: MRPT %.4f (valid %d), world %.4f, aperture %.4f\n", i,
                       obs.getScanRange(i), obs.getScanRangeValidity(i) ? 1 : 0, want, obs.aperture);
      } else {
        ++compared;
      }
    }
    if (failures > 0) return 1;
    ++good;
    std::printf("scan %d: %zu values, %d compared, aperture %.4f rad, rightToLeft %d\n", good, obs.getScanSize(),
                compared, obs.aperture, obs.rightToLeft ? 1 : 0);
  }
  std::uint64_t requests = 0;
  std::uint64_t writes = 0;
  std::uint32_t baud = 0;
  print_requests(**runner);
  (*runner)->with_emulator([&](Lms200Emulator& e) {
    requests = e.counters().requests;
    writes = e.counters().config_writes;
    baud = e.baud();
  });
  std::printf("ok: %d scans at %u baud, %s, %d/%d; emulator saw %llu requests, %llu config writes\n", good, baud,
              a.mm ? "mm" : "cm", a.fov_deg, a.res_cdeg, static_cast<unsigned long long>(requests),
              static_cast<unsigned long long>(writes));
  return baud == a.baud ? 0 : 1;
}
