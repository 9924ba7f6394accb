// Release jitter of the scheduler against cyclictest, on this machine.
//
// For 100 Hz and 1 kHz, idle and with the other core(s) loaded by busy threads, it runs one
// real-time task on the scheduler for --seconds (default 10) and reports the task's release
// jitter (start - release) p50/p99/max; then runs cyclictest (Debian rt-tests) with the same
// interval, priority and duration, reads its latency histogram, and prints the ratio of our
// p99 to cyclictest's. It prints numbers; it asserts nothing.
//
// usage: sen3bot_jitter_bench [--seconds S] [--priority P] [--cpu N] [--no-cyclictest]
#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/rt_setup.hpp"
#include "sen3bot/tasks/scheduler.hpp"

namespace {

using namespace sen3bot;

struct Options {
  double seconds = 10;
  int priority = 80;
  int cpu = 0;
  bool cyclictest = true;
};

struct Figures {
  bool valid = false;
  double p50_us = 0, p99_us = 0, max_us = 0;
  std::uint64_t samples = 0;
};

class NopTask final : public tasks::Task {
 public:
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const tasks::StepContext&) override {}
};

// Busy threads on every CPU but the measured one: "the other core loaded".
class Load {
 public:
  Load(int measured_cpu, bool enabled) {
    if (!enabled) return;
    const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
    for (unsigned c = 0; c < cpus; ++c) {
      if (static_cast<int>(c) == measured_cpu && cpus > 1) continue;
      threads_.emplace_back([this, c] {
        (void)hal::set_current_thread_affinity(static_cast<int>(c));
        volatile std::uint64_t x = 0;
        while (!stop_.load(std::memory_order_relaxed)) x = x * 6364136223846793005ull + 1;
      });
    }
  }
  ~Load() {
    stop_ = true;
    for (auto& t : threads_) t.join();
  }
  [[nodiscard]] std::size_t threads() const { return threads_.size(); }

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

Figures measure_scheduler(const Options& o, std::int64_t period_us, std::string& notes) {
  hal::PosixClock clock;
  tasks::Scheduler scheduler(clock);
  NopTask task;
  if (!scheduler.add({"probe", period_us, period_us, o.priority, "rt"}, task)) return {};
  (void)scheduler.configure_thread({"rt", o.cpu, true, 64 * 1024});
  if (Status s = scheduler.start(); !s) {
    notes = s.error().c_str();
    return {};
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(o.seconds));
  scheduler.request_stop();
  scheduler.join();
  for (std::size_t i = 0; i < scheduler.warning_count(); ++i) notes += std::string(scheduler.warning(i).message()) + "; ";
  const tasks::TaskStats s = scheduler.stats(0);
  Figures f;
  f.valid = s.runs > 0;
  f.samples = s.runs;
  f.p50_us = static_cast<double>(s.jitter_p50_ns) / 1e3;
  f.p99_us = static_cast<double>(s.jitter_p99_ns) / 1e3;
  f.max_us = static_cast<double>(s.jitter_max_ns) / 1e3;
  return f;
}

// cyclictest -h prints one line per microsecond bucket: "000123 000000042".
Figures measure_cyclictest(const Options& o, std::int64_t period_us, bool with_priority, std::string& notes) {
  constexpr int kHistogramMaxUs = 20'000;
  char command[512];
  std::snprintf(command, sizeof command,
                "cyclictest -q -m -t1 -a %d %s -i %" PRId64 " -D %ds -h %d 2>&1", o.cpu,
                with_priority ? ("-p " + std::to_string(o.priority)).c_str() : "", period_us,
                static_cast<int>(o.seconds), kHistogramMaxUs);
  std::FILE* pipe = popen(command, "r");
  if (pipe == nullptr) {
    notes = "cannot start cyclictest";
    return {};
  }
  std::vector<std::uint64_t> histogram(kHistogramMaxUs + 1, 0);
  std::uint64_t total = 0, overflows = 0;
  double max_us = 0;
  char line[512];
  std::string first_error;
  while (std::fgets(line, sizeof line, pipe)) {
    unsigned long long bucket = 0, count = 0;
    if (line[0] != '#' && std::sscanf(line, "%llu %llu", &bucket, &count) == 2) {
      if (bucket <= kHistogramMaxUs) {
        histogram[bucket] += count;
        total += count;
        if (count > 0) max_us = std::max(max_us, static_cast<double>(bucket));
      }
    } else if (std::strncmp(line, "# Histogram Overflows:", 22) == 0) {
      overflows = std::strtoull(line + 22, nullptr, 10);
    } else if (std::strncmp(line, "# Max Latencies:", 16) == 0) {
      max_us = std::max(max_us, std::strtod(line + 16, nullptr));
    } else if (line[0] != '#' && first_error.empty()) {
      first_error = line;
    }
  }
  const int rc = pclose(pipe);
  if (total == 0) {
    notes = "cyclictest failed (exit " + std::to_string(rc) + "): " + first_error;
    return {};
  }
  total += overflows;
  auto percentile = [&](double p) {
    const auto rank = static_cast<std::uint64_t>(p * static_cast<double>(total) + 0.5);
    std::uint64_t seen = 0;
    for (std::size_t us = 0; us < histogram.size(); ++us) {
      seen += histogram[us];
      if (seen >= rank) return static_cast<double>(us);
    }
    return max_us;
  };
  Figures f;
  f.valid = true;
  f.samples = total;
  f.p50_us = percentile(0.50);
  f.p99_us = percentile(0.99);
  f.max_us = max_us;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc) o.seconds = std::atof(argv[++i]);
    else if (a == "--priority" && i + 1 < argc) o.priority = std::atoi(argv[++i]);
    else if (a == "--cpu" && i + 1 < argc) o.cpu = std::atoi(argv[++i]);
    else if (a == "--no-cyclictest") o.cyclictest = false;
    else {
      std::fprintf(stderr, "usage: %s [--seconds S] [--priority P] [--cpu N] [--no-cyclictest]\n", argv[0]);
      return 2;
    }
  }
  const Status locked = hal::lock_memory();
  std::printf("release jitter, %g s per case, task pinned to cpu %d, priority %d (%u cpus, memory %s)\n", o.seconds,
              o.cpu, o.priority, std::thread::hardware_concurrency(),
              locked ? "locked" : "not locked");
  // Probe whether SCHED_FIFO is permitted, so cyclictest is run the same way as we are.
  bool fifo_ok = false;
  std::thread([&] { fifo_ok = hal::set_current_thread_fifo(o.priority).ok(); }).join();
  std::printf("SCHED_FIFO %s\n\n", fifo_ok ? "permitted: both measured at real-time priority"
                                          : "not permitted: both measured at normal priority");

  std::printf("%-7s %-7s %-11s %9s %9s %9s %9s   %s\n", "rate", "load", "measured", "samples", "p50_us", "p99_us",
              "max_us", "p99 ratio (ours / cyclictest)");
  for (std::int64_t period_us : {10'000, 1'000}) {
    for (bool loaded : {false, true}) {
      std::string notes_ours, notes_ct;
      Figures ours, ct;
      {
        Load load(o.cpu, loaded);
        ours = measure_scheduler(o, period_us, notes_ours);
      }
      if (o.cyclictest) {
        Load load(o.cpu, loaded);
        ct = measure_cyclictest(o, period_us, fifo_ok, notes_ct);
      }
      const char* rate = period_us == 10'000 ? "100Hz" : "1kHz";
      const char* load_name = loaded ? "loaded" : "idle";
      auto row = [&](const char* who, const Figures& f, const std::string& notes) {
        if (f.valid)
          std::printf("%-7s %-7s %-11s %9" PRIu64 " %9.1f %9.1f %9.1f", rate, load_name, who, f.samples, f.p50_us,
                      f.p99_us, f.max_us);
        else
          std::printf("%-7s %-7s %-11s %9s (%s)", rate, load_name, who, "-", notes.c_str());
      };
      row("scheduler", ours, notes_ours);
      std::printf("\n");
      if (o.cyclictest) {
        row("cyclictest", ct, notes_ct);
        if (ours.valid && ct.valid && ct.p99_us > 0) std::printf("   %.2f", ours.p99_us / ct.p99_us);
        std::printf("\n");
      }
    }
  }
  return 0;
}
