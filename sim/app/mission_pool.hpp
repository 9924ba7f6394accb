#pragma once
// The experiments' worker pool (`experiment dol`, `experiment crowd`): every job (a whole
// firmware mission in lockstep) runs in a forked worker process, which sends each job's result,
// a fixed-size trivially copyable value, through its own pipe. Worker w of n runs jobs w, w + n,
// ... in order, so a job's result never depends on how many workers there are; results[j] is
// job j's. Header-only: a template over the result type.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

namespace sen3bot::sim::pool {

// The most runs one experiment command takes (--runs).
inline constexpr std::uint64_t kMaxRuns = 100000;

template <class R>
struct Callbacks {
  // In the worker: runs job j and returns its result.
  std::function<R(std::size_t j)> run;
  // In the parent, as each result arrives (per worker in job order): "" to keep it (progress
  // lines may be printed here), or why the experiment must stop (the mission could not run).
  std::function<std::string(std::size_t j, const R& result)> accept;
  // Names job j in a message about a worker that died running it, e.g. "seed 22 (DOL)".
  std::function<std::string(std::size_t j)> describe;
};

namespace detail {

inline bool write_all(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

inline std::string describe_exit(int status) {
  char text[96];
  if (WIFSIGNALED(status))
    std::snprintf(text, sizeof text, "killed by signal %d (%s)", WTERMSIG(status), strsignal(WTERMSIG(status)));
  else if (WIFEXITED(status))
    std::snprintf(text, sizeof text, "exited with status %d", WEXITSTATUS(status));
  else
    std::snprintf(text, sizeof text, "ended (status %d)", status);
  return text;
}

// What goes through the pipe: the job's index and its result.
template <class R>
struct Envelope {
  std::uint64_t job = 0;
  R result{};
};

struct Worker {
  pid_t pid = -1;
  int fd = -1;
  std::size_t next = 0;  // the job whose result comes next
  std::vector<char> buffer;
};

}  // namespace detail

// Runs jobs 0..jobs-1 on `workers` processes (at most one per job). False, after a message on
// err prefixed with `name`, when a worker died (naming its job with describe()), sent results
// out of order, or accept() refused a result; the other workers are then killed.
template <class R>
bool run_pool(const char* name, std::size_t jobs, std::size_t workers, const Callbacks<R>& callbacks, std::vector<R>& results,
              std::FILE* out, std::FILE* err) {
  static_assert(std::is_trivially_copyable_v<R>, "results go through a pipe as bytes");
  using Envelope = detail::Envelope<R>;
  results.assign(jobs, R{});
  if (jobs == 0) return true;
  workers = std::max<std::size_t>(1, std::min(workers, jobs));
  std::fflush(out);
  std::fflush(err);
  std::fflush(stdout);
  std::fflush(stderr);
  std::vector<detail::Worker> pool(workers);
  for (std::size_t w = 0; w < workers; ++w) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
      std::fprintf(err, "%s: pipe: %s\n", name, std::strerror(errno));
      return false;
    }
    const pid_t pid = ::fork();
    if (pid < 0) {
      std::fprintf(err, "%s: fork: %s\n", name, std::strerror(errno));
      ::close(fds[0]);
      ::close(fds[1]);
      for (std::size_t k = 0; k < w; ++k) {
        ::kill(pool[k].pid, SIGKILL);
        ::waitpid(pool[k].pid, nullptr, 0);
        ::close(pool[k].fd);
      }
      return false;
    }
    if (pid == 0) {
      // The worker: jobs w, w + n, ... in order; never returns.
      ::close(fds[0]);
      for (std::size_t k = 0; k < w; ++k) ::close(pool[k].fd);
      for (std::size_t j = w; j < jobs; j += workers) {
        Envelope e;
        e.job = j;
        e.result = callbacks.run(j);
        if (!detail::write_all(fds[1], &e, sizeof e)) ::_exit(1);
      }
      ::close(fds[1]);
      ::_exit(0);
    }
    ::close(fds[1]);
    pool[w].pid = pid;
    pool[w].fd = fds[0];
    pool[w].next = w;
  }

  std::string failure;
  std::size_t open = workers;
  auto stop_all = [&] {
    for (detail::Worker& k : pool)
      if (k.fd >= 0) ::kill(k.pid, SIGKILL);
  };
  while (open > 0) {
    std::vector<pollfd> fds;
    std::vector<std::size_t> owner;
    for (std::size_t w = 0; w < pool.size(); ++w)
      if (pool[w].fd >= 0) {
        fds.push_back({pool[w].fd, POLLIN, 0});
        owner.push_back(w);
      }
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      std::fprintf(err, "%s: poll: %s\n", name, std::strerror(errno));
      stop_all();
      failure = "poll failed";
    }
    for (std::size_t i = 0; i < fds.size(); ++i) {
      if (fds[i].revents == 0 && failure.empty()) continue;
      detail::Worker& k = pool[owner[i]];
      char chunk[4096];
      const ssize_t n = failure.empty() ? ::read(k.fd, chunk, sizeof chunk) : 0;
      if (n < 0 && errno == EINTR) continue;
      if (n > 0) {
        k.buffer.insert(k.buffer.end(), chunk, chunk + n);
        while (k.buffer.size() >= sizeof(Envelope)) {
          Envelope e;
          std::memcpy(&e, k.buffer.data(), sizeof e);
          k.buffer.erase(k.buffer.begin(), k.buffer.begin() + static_cast<std::ptrdiff_t>(sizeof e));
          if (e.job != k.next || k.next >= jobs) {
            if (failure.empty()) failure = "a worker sent a result out of order";
            stop_all();
            break;
          }
          k.next += workers;
          if (std::string refused = callbacks.accept(e.job, e.result); !refused.empty()) {
            if (failure.empty()) failure = std::move(refused);
            stop_all();
            continue;
          }
          results[e.job] = e.result;
        }
        continue;
      }
      // End of the pipe: the worker is done, or died.
      int status = 0;
      while (::waitpid(k.pid, &status, 0) < 0 && errno == EINTR) {
      }
      ::close(k.fd);
      k.fd = -1;
      --open;
      const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
      if ((!clean || k.next < jobs) && failure.empty()) {
        failure = "worker " + std::to_string(k.pid) + " " + detail::describe_exit(status) + " while running " +
                  callbacks.describe(std::min(k.next, jobs - 1));
        stop_all();
      }
    }
  }
  if (!failure.empty()) {
    std::fprintf(err, "%s: %s\n", name, failure.c_str());
    return false;
  }
  return true;
}

}  // namespace sen3bot::sim::pool
