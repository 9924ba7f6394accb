#pragma once
// A program of this build under test as a child process, its standard output and error in
// files: started with posix_spawn, signalled, waited for with a deadline, killed when the
// object goes away. A cross build runs its tests under CMake's cross-compiling emulator
// (qemu-user with the sysroot); the child goes through the same emulator, named explicitly,
// never through whatever binfmt registration the host happens to have.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

extern char** environ;

// The emulator's command line with its words joined by '|' (tests/CMakeLists.txt); native
// builds define nothing.
#ifndef SEN3BOT_TEST_EMULATOR
#define SEN3BOT_TEST_EMULATOR ""
#endif

namespace sen3bot::testing {

// `args` (a program of this build and its arguments) prefixed with the emulator's words.
inline std::vector<std::string> built_program(std::vector<std::string> args) {
  std::vector<std::string> command;
  std::string_view rest = SEN3BOT_TEST_EMULATOR;
  while (!rest.empty()) {
    const std::size_t bar = rest.find('|');
    command.emplace_back(rest.substr(0, bar));
    rest = bar == std::string_view::npos ? std::string_view{} : rest.substr(bar + 1);
  }
  command.insert(command.end(), std::make_move_iterator(args.begin()), std::make_move_iterator(args.end()));
  return command;
}

inline std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class ChildProcess {
 public:
  ChildProcess(std::vector<std::string> args, const std::string& out_path, const std::string& err_path)
      : out_(out_path), err_(err_path) {
    args = built_program(std::move(args));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~ChildProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  [[nodiscard]] bool started() const noexcept { return pid_ > 0; }
  void signal(int sig) const {
    if (pid_ > 0) ::kill(pid_, sig);
  }
  // The exit status (128 + signal when killed), or -1 when it did not end within timeout_s.
  int wait(double timeout_s = 10.0) {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    while (pid_ > 0) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (Clock::now() > deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }
  [[nodiscard]] std::string out() const { return read_text_file(out_); }
  [[nodiscard]] std::string err() const { return read_text_file(err_); }

 private:
  pid_t pid_ = -1;
  std::string out_, err_;
};

}  // namespace sen3bot::testing
