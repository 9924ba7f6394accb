#pragma once
// A real Eclipse Mosquitto broker for tests: the shipped site configuration
// (config/mosquitto) with its paths moved into a temporary folder, certificates from
// toolchain/broker-pki.sh and users from mosquitto_passwd; or a plain loopback listener.
// The broker runs as a child process and can be killed and started again on the same port.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

extern char** environ;

namespace sen3bot::testing {

inline int free_tcp_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t size = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size);
  ::close(fd);
  return ntohs(address.sin_port);
}

inline bool port_accepts(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return ok;
}

inline int run_command(const std::string& command) { return std::system(command.c_str()); }

class MosquittoBroker {
 public:
  struct User {
    std::string name;
    std::string password;
  };

  // A plain listener on loopback, anonymous clients allowed.
  static MosquittoBroker plain() {
    MosquittoBroker broker;
    broker.port_ = free_tcp_port();
    broker.write_config("listener " + std::to_string(broker.port_) + " 127.0.0.1\nallow_anonymous true\n");
    return broker;
  }

  // The shipped configuration, TLS on a free loopback port, with these users.
  static MosquittoBroker site(const std::vector<User>& users) {
    MosquittoBroker broker;
    broker.port_ = free_tcp_port();
    const std::string dir = broker.dir_;
    if (run_command(std::string(SEN3BOT_SOURCE_DIR) + "/toolchain/broker-pki.sh " + dir + " localhost >/dev/null") != 0) {
      throw std::runtime_error("broker-pki.sh failed");
    }
    for (std::size_t i = 0; i < users.size(); ++i) {
      const std::string create = i == 0 ? "-c " : "";
      if (run_command("mosquitto_passwd " + create + "-b " + dir + "/passwd " + users[i].name + " " + users[i].password) != 0) {
        throw std::runtime_error("mosquitto_passwd failed");
      }
    }
    std::string acl = read(std::string(SEN3BOT_SOURCE_DIR) + "/config/mosquitto/acl");
    std::ofstream(dir + "/acl") << acl;
    std::string config = read(std::string(SEN3BOT_SOURCE_DIR) + "/config/mosquitto/mosquitto.conf");
    replace_all(config, "/etc/mosquitto/sen3bot", dir);
    replace_all(config, "listener 8883", "listener " + std::to_string(broker.port_) + " 127.0.0.1");
    broker.write_config(config);
    // Started as root, Mosquitto drops to its own user before reading these.
    run_command("chmod -R a+rX " + dir);
    return broker;
  }

  MosquittoBroker(MosquittoBroker&& other) noexcept
      : dir_(std::exchange(other.dir_, {})), port_(other.port_), pid_(std::exchange(other.pid_, -1)) {}
  MosquittoBroker& operator=(MosquittoBroker&&) = delete;
  ~MosquittoBroker() {
    kill();
    if (!dir_.empty()) run_command("rm -rf " + dir_);
  }

  [[nodiscard]] int port() const noexcept { return port_; }
  [[nodiscard]] const std::string& dir() const noexcept { return dir_; }
  [[nodiscard]] std::string ca_file() const { return dir_ + "/ca.crt"; }
  [[nodiscard]] std::string url(const char* scheme = "mqtt") const {
    return std::string(scheme) + "://127.0.0.1:" + std::to_string(port_);
  }

  // Starts the broker and waits until it accepts connections.
  void start() {
    // Spawned, not forked: the test process may already run client threads (a restart), and
    // a fork of those is unsafe (and under qemu-user, unreliable).
    const std::string log = dir_ + "/mosquitto.log";
    std::string config = dir_ + "/mosquitto.conf";
    std::string program = "mosquitto", flag = "-c";
    char* argv[] = {program.data(), flag.data(), config.data(), nullptr};
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    const int spawned = ::posix_spawnp(&pid_, "mosquitto", &actions, nullptr, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) {
      pid_ = -1;
      throw std::runtime_error("cannot start mosquitto: " + std::string(std::strerror(spawned)));
    }
    for (int i = 0; i < 500; ++i) {
      if (port_accepts(port_)) return;
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("mosquitto exited at start: " + read(dir_ + "/mosquitto.log"));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    throw std::runtime_error("mosquitto did not listen within 5 s");
  }

  // SIGKILL: the broker vanishes without closing anything.
  void kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

  [[nodiscard]] std::string log() const { return read(dir_ + "/mosquitto.log"); }

 private:
  MosquittoBroker() {
    char path[] = "/tmp/sen3bot-mosquitto-XXXXXX";
    if (::mkdtemp(path) == nullptr) throw std::runtime_error("mkdtemp failed");
    dir_ = path;
  }
  void write_config(const std::string& text) {
    std::ofstream(dir_ + "/mosquitto.conf") << text << "persistence false\nlog_dest stderr\nlog_type error\nlog_type warning\n";
  }
  static std::string read(const std::string& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  static void replace_all(std::string& text, const std::string& from, const std::string& to) {
    for (std::size_t pos = text.find(from); pos != std::string::npos; pos = text.find(from, pos + to.size())) {
      text.replace(pos, from.size(), to);
    }
  }

  std::string dir_;
  int port_ = 0;
  pid_t pid_ = -1;
};

}  // namespace sen3bot::testing
