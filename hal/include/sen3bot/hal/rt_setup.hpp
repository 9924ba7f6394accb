#pragma once
// Real-time process and thread set-up. Every step reports {ok | why not} and never aborts,
// so the same binary runs on the robot's computer (capabilities granted) and on a laptop
// or CI machine (warned, runs best-effort).
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

// mlockall(MCL_CURRENT | MCL_FUTURE): no page faults to disk in the control loop.
// Needs CAP_IPC_LOCK or an RLIMIT_MEMLOCK larger than the process.
Status lock_memory();
Status unlock_memory();  // munlockall, for tests and orderly shutdown

// Touches bytes of the calling thread's stack now, so the first deep call in the loop does
// not page-fault (effective together with lock_memory). Errc::invalid_argument if the
// stack has less room than that.
Status prefault_stack(std::size_t bytes);

// The stack size of threads started from now on that do not choose their own (std::thread never
// does). glibc otherwise gives each RLIMIT_STACK, 8 MiB on Debian, all of which lock_memory()
// then keeps resident. Errc::invalid_argument below PTHREAD_STACK_MIN.
Status set_default_thread_stack(std::size_t bytes);

// SCHED_FIFO at priority (1..99) for the calling thread. Needs CAP_SYS_NICE or an
// RLIMIT_RTPRIO of at least priority; the Error says so.
Status set_current_thread_fifo(int priority);

// Pins the calling thread to one CPU (0-based).
Status set_current_thread_affinity(int cpu);

// Holds a PM QoS request on /dev/cpu_dma_latency for as long as it lives: the CPUs stay out of
// idle states whose exit takes longer than max_latency_us, so a sleeping real-time thread
// wakes on time. Deep C-states (or, in a VM, halting the vCPU) add tens to hundreds of
// microseconds to every wake-up; cyclictest makes the same request by default. Needs write
// access to the device (root, or a udev rule on the robot); the Error says so.
class CpuLatencyRequest {
 public:
  CpuLatencyRequest() = default;
  ~CpuLatencyRequest();
  CpuLatencyRequest(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest& operator=(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;

  // The request is dropped when the object (its file descriptor) goes.
  static Result<CpuLatencyRequest> hold(std::int32_t max_latency_us,
                                        const char* device = "/dev/cpu_dma_latency");
  [[nodiscard]] bool active() const noexcept { return fd_ >= 0; }

 private:
  explicit CpuLatencyRequest(int fd) : fd_(fd) {}
  int fd_ = -1;
};

struct RtSetupOptions {
  bool lock_memory = true;
  std::size_t prefault_stack_bytes = 256 * 1024;  // 0 skips the step
  int fifo_priority = 0;                          // 0 keeps the normal scheduler
  int cpu = -1;                                   // -1 keeps the current affinity
};

struct RtStepResult {
  std::string_view step;  // "lock memory", "prefault stack", ...
  bool attempted = false;
  Status status;
};

struct RtSetupReport {
  std::array<RtStepResult, 4> steps{};
  [[nodiscard]] bool all_ok() const noexcept;
};

// Runs the requested steps for the calling thread, all of them even if one fails.
RtSetupReport apply_rt_setup(const RtSetupOptions& options);

// One line per step, for the start-up log:
//   lock memory: ok
//   SCHED_FIFO: FAILED (permission) SCHED_FIFO priority 80 not permitted (...)
std::string describe(const RtSetupReport& report);

}  // namespace sen3bot::hal
