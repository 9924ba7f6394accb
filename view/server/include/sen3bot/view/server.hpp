#pragma once
// The live view's server: one port that answers the built-in page over HTTP and the
// foxglove.websocket.v1 subprotocol over WebSocket (libwebsockets), on its own thread. The view
// task publishes channel messages into the board and calls notify(); the server sends each
// subscribed client the newest message of each channel whenever that client's socket can take
// it, so a slow or stalled client only misses messages and never holds anyone up.
//
// Security: it binds the configured address only; a peer that is not loopback must give the
// access token (?token= or Authorization: Bearer), and without a token configured the server
// refuses to bind anything but loopback. No channel takes anything from a client.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <span>
#include <string>
#include <thread>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/view/channel_board.hpp"

struct lws;
struct lws_context;

namespace sen3bot::view {

struct ServerConfig {
  std::string address = "127.0.0.1";
  int port = 8765;  // 0: any free port (port() tells which)
  std::string token;  // required of non-loopback peers; empty: loopback only
  std::size_t max_clients = 4;
  std::string name = "sen3bot";
};

struct ServerCounters {
  std::uint64_t clients = 0;          // connected WebSocket clients now
  std::uint64_t connections = 0;      // WebSocket clients accepted so far
  std::uint64_t sent = 0;             // message data frames sent
  std::uint64_t sent_bytes = 0;
  std::uint64_t dropped = 0;          // newer messages superseded before a client could take them
  std::uint64_t rejected = 0;         // refused connections (token, subprotocol, full) and requests
  std::uint64_t refused_ops = 0;      // client operations answered with an error status
  std::uint64_t closed_oversized = 0; // clients closed for a message over the limit
  std::uint64_t pages = 0;            // pages served over HTTP
};

// True for 127.0.0.0/8, ::1 and ::ffff:127.x.
bool is_loopback_address(std::string_view address) noexcept;
// Constant-time comparison of a presented token with the configured one.
bool token_matches(std::string_view presented, std::string_view expected) noexcept;

class Server {
 public:
  static constexpr std::size_t kMaxClients = 16;
  static constexpr std::size_t kMaxClientMessageBytes = 64 * 1024;

  // Checks the configuration and takes all its memory from `memory`: the board's buffers, the
  // client slots and the control messages (libwebsockets keeps its own per connection).
  static Result<std::unique_ptr<Server>> create(const ServerConfig& config, std::span<const ChannelSpec> channels,
                                                std::pmr::memory_resource& memory);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds and starts the service thread.
  Status start();
  void stop();
  [[nodiscard]] bool running() const noexcept { return running_.load(std::memory_order_acquire); }
  [[nodiscard]] int port() const noexcept { return port_; }
  [[nodiscard]] const ServerConfig& config() const noexcept { return config_; }

  [[nodiscard]] ChannelBoard& board() noexcept { return *board_; }
  // After publishing: wakes the service thread (thread-safe, no allocation).
  void notify() noexcept;
  [[nodiscard]] ServerCounters counters() const noexcept;
  // CPU time the service thread has used (0 when not running), for the benchmark.
  [[nodiscard]] std::int64_t thread_cpu_ns() noexcept;
  // The memory taken at create(), for the budget.
  [[nodiscard]] std::size_t bytes() const noexcept;

  // libwebsockets' callback, forwarded to the instance.
  int on_event(lws* wsi, int reason, void* user, void* in, std::size_t len);

 private:
  struct Client;
  struct Impl;
  struct Connection;
  Server() = default;
  void run();
  // on_event's steps, by event.
  int serve_page(lws* wsi, Connection* connection, std::string_view path);
  int send_page(lws* wsi, Connection& connection);
  int admit(lws* wsi);
  int open_client(lws* wsi, Connection* connection);
  int receive(lws* wsi, Client& client, const void* in, std::size_t len);
  int send_next(lws* wsi, Client& client);
  int send_record(lws* wsi, Client& client);
  void wake_writers();

  ServerConfig config_;
  std::unique_ptr<ChannelBoard> board_;
  std::pmr::memory_resource* memory_ = nullptr;
  Impl* impl_ = nullptr;
  Client* clients_ = nullptr;
  std::size_t client_slots_ = 0;
  lws_context* context_ = nullptr;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stopping_{false};
  int port_ = 0;
};

}  // namespace sen3bot::view
