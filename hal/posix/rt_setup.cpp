#include <alloca.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>

#include "posix_error.hpp"
#include "sen3bot/hal/rt_setup.hpp"

namespace sen3bot::hal {

namespace {

// Room kept free below the prefaulted region for the calls the thread still makes.
constexpr std::size_t kStackSafetyMarginBytes = 64 * 1024;

// The lowest address of the calling thread's stack and its size, or false if unknown.
bool thread_stack(char*& low, std::size_t& size) {
  pthread_attr_t attributes;
  if (::pthread_getattr_np(::pthread_self(), &attributes) != 0) return false;
  void* address = nullptr;
  const bool ok = ::pthread_attr_getstack(&attributes, &address, &size) == 0;
  ::pthread_attr_destroy(&attributes);
  low = static_cast<char*>(address);
  return ok;
}

// noinline: the alloca must live in its own frame, below the caller's.
[[gnu::noinline]] void touch_stack(std::size_t bytes, std::size_t page_bytes) {
  auto* region = static_cast<volatile char*>(alloca(bytes));
  for (std::size_t offset = 0; offset < bytes; offset += page_bytes) region[offset] = 0;
  region[bytes - 1] = 0;
}

std::string cpu_list(const cpu_set_t& set) {
  std::string text;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (!CPU_ISSET(cpu, &set)) continue;
    if (!text.empty()) text += ',';
    text += std::to_string(cpu);
  }
  return text.empty() ? "none" : text;
}

}  // namespace

Status lock_memory() {
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return {};
  const int err = errno;
  rlimit limit{};
  ::getrlimit(RLIMIT_MEMLOCK, &limit);
  const unsigned long limit_kib = limit.rlim_cur == RLIM_INFINITY ? 0 : static_cast<unsigned long>(limit.rlim_cur / 1024);
  if (err == EPERM) {
    return posix::errno_error(Errc::permission, err, "mlockall not permitted (needs CAP_IPC_LOCK)");
  }
  if (err == ENOMEM) {
    return posix::errno_error(Errc::permission, err,
                              "mlockall: the process is larger than RLIMIT_MEMLOCK (%lu KiB); raise it or grant CAP_IPC_LOCK",
                              limit_kib);
  }
  return posix::errno_error(Errc::io, err, "mlockall(MCL_CURRENT|MCL_FUTURE)");
}

Status unlock_memory() {
  if (::munlockall() == 0) return {};
  const int err = errno;
  return posix::errno_error(Errc::io, err, "munlockall");
}

Status prefault_stack(std::size_t bytes) {
  if (bytes == 0) return {};
  char* low = nullptr;
  std::size_t size = 0;
  if (thread_stack(low, size)) {
    // The frame's address, not a local's: under AddressSanitizer's use-after-return detection
    // locals live on a heap-allocated fake stack.
    const char* here = static_cast<const char*>(__builtin_frame_address(0));
    // Stacks grow down on every target we build for (x86-64, AArch64, ARMv7).
    const std::size_t room = static_cast<std::size_t>(here - low);
    if (bytes + kStackSafetyMarginBytes > room) {
      return Error::format(Errc::invalid_argument,
                           "prefault_stack: %zu bytes asked but only %zu of the %zu-byte stack are free "
                           "(keeping %zu spare)",
                           bytes, room, size, kStackSafetyMarginBytes);
    }
  }
  const long page = ::sysconf(_SC_PAGESIZE);
  touch_stack(bytes, page > 0 ? static_cast<std::size_t>(page) : 4096);
  return {};
}

Status set_default_thread_stack(std::size_t bytes) {
  if (bytes < static_cast<std::size_t>(PTHREAD_STACK_MIN))
    return Error::format(Errc::invalid_argument, "thread stack: %zu bytes is below the minimum (%zu)", bytes,
                         static_cast<std::size_t>(PTHREAD_STACK_MIN));
  pthread_attr_t attr;
  int err = ::pthread_getattr_default_np(&attr);
  if (err != 0) return posix::errno_error(Errc::io, err, "pthread_getattr_default_np");
  err = ::pthread_attr_setstacksize(&attr, bytes);
  if (err == 0) err = ::pthread_setattr_default_np(&attr);
  ::pthread_attr_destroy(&attr);
  if (err != 0) return posix::errno_error(Errc::io, err, "thread stack: %zu bytes", bytes);
  return {};
}

Status set_current_thread_fifo(int priority) {
  const int min_priority = ::sched_get_priority_min(SCHED_FIFO);
  const int max_priority = ::sched_get_priority_max(SCHED_FIFO);
  if (priority < min_priority || priority > max_priority) {
    return Error::format(Errc::invalid_argument, "SCHED_FIFO priority %d outside %d..%d", priority, min_priority,
                         max_priority);
  }
  sched_param parameters{};
  parameters.sched_priority = priority;
  // pthread_setschedparam returns the error instead of setting errno.
  const int err = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &parameters);
  if (err == 0) return {};
  if (err == EPERM) {
    return posix::errno_error(Errc::permission, err,
                              "SCHED_FIFO priority %d not permitted (needs CAP_SYS_NICE or RLIMIT_RTPRIO)", priority);
  }
  return posix::errno_error(Errc::io, err, "SCHED_FIFO priority %d", priority);
}

Status set_current_thread_affinity(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE) {
    return Error::format(Errc::invalid_argument, "CPU %d outside 0..%d", cpu, CPU_SETSIZE - 1);
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int err = ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set);
  if (err == 0) return {};
  if (err == EINVAL) {
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    ::sched_getaffinity(0, sizeof allowed, &allowed);
    const std::string list = cpu_list(allowed);
    return Error::format(Errc::invalid_argument, "CPU %d is not available to this process (allowed: %s)", cpu,
                         list.c_str());
  }
  return posix::errno_error(err == EPERM ? Errc::permission : Errc::io, err, "pinning the thread to CPU %d", cpu);
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);
}

CpuLatencyRequest::CpuLatencyRequest(CpuLatencyRequest&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

CpuLatencyRequest& CpuLatencyRequest::operator=(CpuLatencyRequest&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

Result<CpuLatencyRequest> CpuLatencyRequest::hold(std::int32_t max_latency_us, const char* device) {
  if (max_latency_us < 0) {
    return Error::format(Errc::invalid_argument, "CPU wake-up latency %d us: must be 0 or more", max_latency_us);
  }
  const int fd = ::open(device, O_WRONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    return posix::errno_error(err == EACCES || err == EPERM ? Errc::permission : Errc::io, err,
                              "%s: cannot request a CPU wake-up latency of %d us", device, max_latency_us);
  }
  // The device takes a binary 32-bit value; the request lasts while the descriptor is open.
  const std::int32_t value = max_latency_us;
  if (::write(fd, &value, sizeof value) != static_cast<ssize_t>(sizeof value)) {
    const int err = errno;
    ::close(fd);
    return posix::errno_error(Errc::io, err, "%s: writing the latency request", device);
  }
  return CpuLatencyRequest(fd);
}

bool RtSetupReport::all_ok() const noexcept {
  for (const RtStepResult& step : steps) {
    if (step.attempted && !step.status.ok()) return false;
  }
  return true;
}

RtSetupReport apply_rt_setup(const RtSetupOptions& options) {
  RtSetupReport report;
  report.steps[0].step = "lock memory";
  report.steps[1].step = "prefault stack";
  report.steps[2].step = "SCHED_FIFO";
  report.steps[3].step = "CPU affinity";
  // Memory first: the prefault then also locks the touched stack pages.
  if (options.lock_memory) {
    report.steps[0].attempted = true;
    report.steps[0].status = lock_memory();
  }
  if (options.prefault_stack_bytes > 0) {
    report.steps[1].attempted = true;
    report.steps[1].status = prefault_stack(options.prefault_stack_bytes);
  }
  if (options.fifo_priority != 0) {
    report.steps[2].attempted = true;
    report.steps[2].status = set_current_thread_fifo(options.fifo_priority);
  }
  if (options.cpu >= 0) {
    report.steps[3].attempted = true;
    report.steps[3].status = set_current_thread_affinity(options.cpu);
  }
  return report;
}

std::string describe(const RtSetupReport& report) {
  std::string text;
  for (const RtStepResult& step : report.steps) {
    text += step.step;
    text += ": ";
    if (!step.attempted) {
      text += "skipped";
    } else if (step.status.ok()) {
      text += "ok";
    } else {
      text += "FAILED (";
      text += to_string(step.status.error().code());
      text += ") ";
      text += step.status.error().message();
    }
    text += '\n';
  }
  return text;
}

}  // namespace sen3bot::hal
