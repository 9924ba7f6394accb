// Release jitter of the scheduler against cyclictest, on this machine.
//
// For 100 Hz and 1 kHz, idle and with the other core(s) loaded by busy threads, it measures
// one real-time task on the scheduler and cyclictest (Debian rt-tests) with the same interval,
// priority and CPU, in alternating rounds (--rounds, default 6) that add up to --seconds each,
// so a pause of the machine (a hypervisor's, a burst of interrupts) is as likely to land on
// either. It prints p50/p99/max release jitter (start - release) for both and checks the goals
// p99 <= cyclictest's p99 and max <= 2 x cyclictest's max. Both run with the CPU wake-up
// latency held at 0 (cyclictest's default, the firmware's realtime.max_cpu_wakeup_latency_us).
// It prints numbers; it asserts nothing.
//
// usage: sen3bot_jitter_bench [--seconds S] [--rounds N] [--priority P] [--cpu N] [--no-cyclictest]
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
  int rounds = 6;
  int priority = 80;
  int cpu = 0;
  bool cyclictest = true;
};

constexpr int kHistogramMaxUs = 20'000;

// Release jitter in 1 us buckets (cyclictest's own resolution), merged over rounds.
struct Jitter {
  std::vector<std::uint64_t> histogram = std::vector<std::uint64_t>(kHistogramMaxUs + 1, 0);
  std::uint64_t samples = 0;
  double max_us = 0;
  std::string notes;

  void add(double us) {
    histogram[static_cast<std::size_t>(std::clamp(us, 0.0, static_cast<double>(kHistogramMaxUs)))] += 1;
    ++samples;
    max_us = std::max(max_us, us);
  }
  [[nodiscard]] double percentile(double p) const {
    const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(p * static_cast<double>(samples) + 0.5));
    std::uint64_t seen = 0;
    for (std::size_t us = 0; us < histogram.size(); ++us) {
      seen += histogram[us];
      if (seen >= rank) return static_cast<double>(us);
    }
    return max_us;
  }
};

// Records each run's lateness; the histogram is sized before the scheduler starts.
class ProbeTask final : public tasks::Task {
 public:
  explicit ProbeTask(Jitter& out) : out_(out) {}
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const tasks::StepContext& c) override { out_.add(static_cast<double>(c.start_ns - c.release_ns) / 1e3); }

 private:
  Jitter& out_;
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

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

void measure_scheduler(const Options& o, std::int64_t period_us, double seconds, Jitter& out) {
  hal::PosixClock clock;
  tasks::Scheduler scheduler(clock);
  ProbeTask task(out);
  if (!scheduler.add({"probe", period_us, period_us, o.priority, "rt"}, task)) return;
  (void)scheduler.configure_thread({"rt", o.cpu, true, 64 * 1024});
  if (Status s = scheduler.start(); !s) {
    out.notes = s.error().c_str();
    return;
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  scheduler.request_stop();
  scheduler.join();
  for (std::size_t i = 0; i < scheduler.warning_count(); ++i)
    out.notes += std::string(scheduler.warning(i).message()) + "; ";
}

// cyclictest -h prints one line per microsecond bucket: "000123 000000042".
void measure_cyclictest(const Options& o, std::int64_t period_us, double seconds, bool with_priority, Jitter& out) {
  char command[512];
  std::snprintf(command, sizeof command, "cyclictest -q -m -t1 -a %d %s -i %" PRId64 " -l %" PRId64 " -h %d 2>&1", o.cpu,
                with_priority ? ("-p " + std::to_string(o.priority)).c_str() : "", period_us,
                std::max<std::int64_t>(1, static_cast<std::int64_t>(seconds * 1e6) / period_us), kHistogramMaxUs);
  std::FILE* pipe = popen(command, "r");
  if (pipe == nullptr) {
    out.notes = "cannot start cyclictest";
    return;
  }
  std::uint64_t counted = 0, overflows = 0;
  char line[512];
  std::string first_error;
  while (std::fgets(line, sizeof line, pipe)) {
    unsigned long long bucket = 0, count = 0;
    if (line[0] != '#' && std::sscanf(line, "%llu %llu", &bucket, &count) == 2) {
      if (bucket <= kHistogramMaxUs) {
        out.histogram[bucket] += count;
        counted += count;
        if (count > 0) out.max_us = std::max(out.max_us, static_cast<double>(bucket));
      }
    } else if (std::strncmp(line, "# Histogram Overflows:", 22) == 0) {
      overflows = std::strtoull(line + 22, nullptr, 10);
    } else if (std::strncmp(line, "# Max Latencies:", 16) == 0) {
      out.max_us = std::max(out.max_us, std::strtod(line + 16, nullptr));
    } else if (line[0] != '#' && first_error.empty()) {
      first_error = line;
    }
  }
  const int rc = pclose(pipe);
  if (counted == 0) {
    out.notes = "cyclictest failed (exit " + std::to_string(rc) + "): " + first_error;
    return;
  }
  out.histogram[kHistogramMaxUs] += overflows;
  out.samples += counted + overflows;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc) o.seconds = std::atof(argv[++i]);
    else if (a == "--rounds" && i + 1 < argc) o.rounds = std::max(1, std::atoi(argv[++i]));
    else if (a == "--priority" && i + 1 < argc) o.priority = std::atoi(argv[++i]);
    else if (a == "--cpu" && i + 1 < argc) o.cpu = std::atoi(argv[++i]);
    else if (a == "--no-cyclictest") o.cyclictest = false;
    else {
      std::fprintf(stderr, "usage: %s [--seconds S] [--rounds N] [--priority P] [--cpu N] [--no-cyclictest]\n",
                   argv[0]);
      return 2;
    }
  }
  const Status locked = hal::lock_memory();
  Result<hal::CpuLatencyRequest> wakeup = hal::CpuLatencyRequest::hold(0);
  std::printf("release jitter, %g s per case in %d alternating rounds, task pinned to cpu %d, priority %d "
              "(%u cpus, memory %s, CPU wake-up latency %s)\n",
              o.seconds, o.rounds, o.cpu, o.priority, std::thread::hardware_concurrency(),
              locked ? "locked" : "not locked", wakeup ? "held at 0 us" : wakeup.error().c_str());
  // Probe whether SCHED_FIFO is permitted, so cyclictest is run the same way as we are.
  bool fifo_ok = false;
  std::thread([&] { fifo_ok = hal::set_current_thread_fifo(o.priority).ok(); }).join();
  std::printf("SCHED_FIFO %s\n\n", fifo_ok ? "permitted: both measured at real-time priority"
                                          : "not permitted: both measured at normal priority");

  std::printf("%-7s %-7s %-11s %9s %9s %9s %9s   %s\n", "rate", "load", "measured", "samples", "p50_us", "p99_us",
              "max_us", "goals: p99 <= cyclictest's, max <= 2 x cyclictest's");
  const double round_s = o.seconds / o.rounds;
  for (std::int64_t period_us : {10'000, 1'000}) {
    for (bool loaded : {false, true}) {
      Jitter ours, ct;
      for (int r = 0; r < o.rounds; ++r) {
        Load load(o.cpu, loaded);
        measure_scheduler(o, period_us, round_s, ours);
        if (o.cyclictest) measure_cyclictest(o, period_us, round_s, fifo_ok, ct);
      }
      const char* rate = period_us == 10'000 ? "100Hz" : "1kHz";
      const char* load_name = loaded ? "loaded" : "idle";
      auto row = [&](const char* who, const Jitter& f) {
        if (f.samples > 0)
          std::printf("%-7s %-7s %-11s %9" PRIu64 " %9.1f %9.1f %9.1f", rate, load_name, who, f.samples,
                      f.percentile(0.50), f.percentile(0.99), f.max_us);
        else
          std::printf("%-7s %-7s %-11s %9s (%s)", rate, load_name, who, "-", f.notes.c_str());
      };
      row("scheduler", ours);
      std::printf("\n");
      if (o.cyclictest) {
        row("cyclictest", ct);
        if (ours.samples > 0 && ct.samples > 0) {
          const double p99_ratio = ours.percentile(0.99) / std::max(1.0, ct.percentile(0.99));
          const double max_ratio = ours.max_us / std::max(1.0, ct.max_us);
          std::printf("   p99 %.2fx %s, max %.2fx %s", p99_ratio, p99_ratio <= 1.0 ? "met" : "MISSED", max_ratio,
                      max_ratio <= 2.0 ? "met" : "MISSED");
        }
        std::printf("\n");
      }
    }
  }
  return 0;
}
