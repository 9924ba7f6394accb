#include "sen3bot/view/server.hpp"

#include <arpa/inet.h>
#include <pthread.h>
#include <signal.h>
#include <libwebsockets.h>
#include <netinet/in.h>
#include <linux/sockios.h>
#include <sys/ioctl.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <mutex>
#include <new>

#include "sen3bot/view/session.hpp"

namespace sen3bot::view {

// The built-in page (view/page/index.html), embedded at build time.
extern const unsigned char kViewPage[];
extern const std::size_t kViewPageSize;

namespace {

constexpr std::size_t kHeadroom = LWS_PRE + kFrameHeader;
constexpr std::size_t kControlBytes = 64 * 1024;  // serverInfo and advertise (the schemas)
constexpr std::size_t kPageChunk = 16 * 1024;
constexpr std::size_t kTokenBytes = 256;

// Content security policy of the page: nothing from anywhere else.
constexpr std::string_view kPagePolicy =
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src blob: data:; "
    "connect-src 'self' ws: wss:; base-uri 'none'; form-action 'none'";

// lws logs through here: errors only, and only the first few, so a hostile peer cannot flood
// the robot's log.
void log_line(int level, const char* line) {
  static std::atomic<unsigned> printed{0};
  if (printed.fetch_add(1, std::memory_order_relaxed) < 20) std::fprintf(stderr, "view: lws %d: %s", level, line);
}

int callback(lws* wsi, enum lws_callback_reasons reason, void* user, void* in, std::size_t len) {
  lws_context* context = lws_get_context(wsi);
  auto* server = context != nullptr ? static_cast<Server*>(lws_context_user(context)) : nullptr;
  if (server == nullptr) return lws_callback_http_dummy(wsi, reason, user, in, len);
  return server->on_event(wsi, static_cast<int>(reason), user, in, len);
}

bool peer_is_loopback(lws* wsi) noexcept {
  sockaddr_storage address{};
  socklen_t size = sizeof address;
  const int fd = lws_get_socket_fd(wsi);
  if (fd < 0 || getpeername(fd, reinterpret_cast<sockaddr*>(&address), &size) != 0) return false;
  char text[INET6_ADDRSTRLEN] = {};
  if (address.ss_family == AF_INET)
    inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(&address)->sin_addr, text, sizeof text);
  else if (address.ss_family == AF_INET6)
    inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(&address)->sin6_addr, text, sizeof text);
  else
    return false;
  return is_loopback_address(text);
}

}  // namespace

// Per connection (lws zeroes it).
struct Server::Connection {
  int client;  // index + 1 of the WebSocket client's slot; 0: none
  bool page;
  std::size_t page_sent;
};

bool is_loopback_address(std::string_view address) noexcept {
  if (address.starts_with("::ffff:")) address.remove_prefix(7);
  if (address == "::1") return true;
  in_addr v4{};
  char text[INET_ADDRSTRLEN] = {};
  if (address.size() >= sizeof text) return false;
  std::memcpy(text, address.data(), address.size());
  return inet_pton(AF_INET, text, &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127;
}

bool token_matches(std::string_view presented, std::string_view expected) noexcept {
  if (expected.empty()) return false;
  // Time depends on the configured token's length only.
  unsigned diff = presented.size() != expected.size() ? 1u : 0u;
  for (std::size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned>(static_cast<unsigned char>(expected[i]) ^
                                  static_cast<unsigned char>(i < presented.size() ? presented[i] : 0));
  return diff == 0;
}

struct Server::Client {
  lws* wsi = nullptr;
  bool need_info = false;
  bool need_advertise = false;
  Session session;
  std::array<std::uint64_t, kMaxChannels> done_seq{};     // the last publish sent whole
  std::array<std::uint64_t, kMaxChannels> sending_seq{};  // the publish being sent
  std::array<std::uint8_t, kMaxChannels> next_record{};
  std::array<std::uint32_t, kMaxChannels> subscribed_as{};
  std::size_t cursor = 0;
  std::size_t rx_size = 0;
  std::array<char, kMaxClientMessageBytes> rx{};
  std::uint64_t refused_seen = 0;
};

struct Server::Impl {
  std::array<char, kControlBytes> server_info{};
  std::size_t server_info_size = 0;
  std::array<char, kControlBytes> advertise{};
  std::size_t advertise_size = 0;
  std::array<char, LWS_PRE + Session::kStatusBytes> status{};
  std::array<char, LWS_PRE + kPageChunk> page{};
  std::array<lws_protocols, 2> protocols{};
  std::atomic<std::uint64_t> clients_now{0}, connections{0}, sent{0}, sent_bytes{0}, dropped{0}, rejected{0},
      refused_ops{0}, closed_oversized{0}, pages{0};
};

Result<std::unique_ptr<Server>> Server::create(const ServerConfig& config, std::span<const ChannelSpec> channels,
                                               std::pmr::memory_resource& memory) {
  in_addr v4{};
  in6_addr v6{};
  if (inet_pton(AF_INET, config.address.c_str(), &v4) != 1 && inet_pton(AF_INET6, config.address.c_str(), &v6) != 1)
    return Error::format(Errc::invalid_argument, "view: address '%s' is not an IPv4 or IPv6 address", config.address.c_str());
  if (!is_loopback_address(config.address) && config.token.empty())
    return Error::format(Errc::invalid_argument,
                         "view: address %s is reachable from other machines: set an access token (view.token)",
                         config.address.c_str());
  if (config.token.size() >= kTokenBytes || config.token.find_first_of(" \t\r\n&#?%+") != std::string::npos)
    return Error::format(Errc::invalid_argument, "view: the token must be under %zu characters, without spaces or &#?%%+",
                         kTokenBytes);
  if (config.port < 0 || config.port > 65535)
    return Error::format(Errc::invalid_argument, "view: port %d out of range", config.port);
  if (config.max_clients < 1 || config.max_clients > kMaxClients)
    return Error::format(Errc::invalid_argument, "view: max_clients %zu (1 to %zu)", config.max_clients, kMaxClients);
  std::unique_ptr<Server> server(new Server());
  server->config_ = config;
  auto board = ChannelBoard::create(channels, kHeadroom, memory);
  if (!board) return board.error();
  server->board_ = std::move(*board);
  server->memory_ = &memory;
  try {
    std::pmr::polymorphic_allocator<Impl> impl_memory(&memory);
    server->impl_ = impl_memory.new_object<Impl>();
    std::pmr::polymorphic_allocator<Client> client_memory(&memory);
    server->clients_ = client_memory.allocate(config.max_clients);
    for (std::size_t i = 0; i < config.max_clients; ++i) std::construct_at(server->clients_ + i);
    server->client_slots_ = config.max_clients;
  } catch (const std::bad_alloc&) {
    return Error(Errc::capacity, "view: out of memory for the client slots");
  }
  Impl& impl = *server->impl_;
  char session_id[32];
  std::snprintf(session_id, sizeof session_id, "%lld", static_cast<long long>(std::time(nullptr)));
  auto info = write_server_info(std::span(impl.server_info).subspan(LWS_PRE), config.name, session_id);
  if (!info) return info.error();
  impl.server_info_size = info->size();
  auto advertise = write_advertise(std::span(impl.advertise).subspan(LWS_PRE), *server->board_);
  if (!advertise) return Error::format(Errc::capacity, "view: the channel advertisement: %s", advertise.error().c_str());
  impl.advertise_size = advertise->size();
  return server;
}

Server::~Server() {
  stop();
  if (clients_ != nullptr) {
    std::destroy_n(clients_, client_slots_);
    std::pmr::polymorphic_allocator<Client>(memory_).deallocate(clients_, client_slots_);
  }
  if (impl_ != nullptr) std::pmr::polymorphic_allocator<Impl>(memory_).delete_object(impl_);
}

std::size_t Server::bytes() const noexcept { return board_->bytes() + sizeof(Impl) + client_slots_ * sizeof(Client); }

Status Server::start() {
  if (running()) return {};
  static std::once_flag log_once;
  std::call_once(log_once, [] { lws_set_log_level(LLL_ERR, log_line); });
  Impl& impl = *impl_;
  lws_protocols& p = impl.protocols[0];
  p.name = kSubprotocol.data();  // a literal: NUL-terminated
  p.callback = callback;
  p.per_session_data_size = sizeof(Connection);
  p.rx_buffer_size = 4096;  // longer client messages arrive in pieces, gathered up to the limit
  // libwebsockets hands the socket at most this much per write and keeps the rest in memory it
  // allocates: a whole message at once, so only the kernel's room decides.
  std::size_t largest = kControlBytes;
  for (std::size_t ch = 0; ch < board_->channel_count(); ++ch) largest = std::max(largest, board_->spec(ch).capacity_bytes);
  p.tx_packet_size = largest + kHeadroom;
  impl.protocols[1] = {};
  lws_context_creation_info info{};
  info.port = config_.port;
  info.iface = config_.address.c_str();
  info.protocols = impl.protocols.data();
  info.gid = static_cast<gid_t>(-1);
  info.uid = static_cast<uid_t>(-1);
  info.user = this;
  info.fd_limit_per_thread = static_cast<unsigned>(2 * config_.max_clients + 16);
  info.options = LWS_SERVER_OPTION_VALIDATE_UTF8;
  if (config_.address.find(':') == std::string::npos) info.options |= LWS_SERVER_OPTION_DISABLE_IPV6;
  info.timeout_secs = 5;  // a handshake or request that takes longer is dropped
  context_ = lws_create_context(&info);
  if (context_ == nullptr)
    return Error::format(Errc::io, "view: cannot listen on %s port %d", config_.address.c_str(), config_.port);
  lws_vhost* vhost = lws_get_vhost_by_name(context_, "default");
  port_ = vhost != nullptr ? lws_get_vhost_listen_port(vhost) : config_.port;
  stopping_.store(false);
  running_.store(true, std::memory_order_release);
  // The service thread takes no signals: SIGINT and SIGTERM stay for the thread that waits for them.
  sigset_t all, previous;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, &previous);
  thread_ = std::thread([this] { run(); });
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  return {};
}

void Server::run() {
  while (!stopping_.load(std::memory_order_acquire))
    if (lws_service(context_, 0) < 0) break;
}

void Server::stop() {
  if (!running()) return;
  stopping_.store(true, std::memory_order_release);
  lws_cancel_service(context_);
  if (thread_.joinable()) thread_.join();
  lws_context_destroy(context_);
  context_ = nullptr;
  for (std::size_t i = 0; i < client_slots_; ++i) clients_[i].wsi = nullptr;
  impl_->clients_now = 0;
  running_.store(false, std::memory_order_release);
}

void Server::notify() noexcept {
  if (running()) lws_cancel_service(context_);
}

std::int64_t Server::thread_cpu_ns() noexcept {
  if (!running() || !thread_.joinable()) return 0;
  clockid_t clock{};
  timespec t{};
  if (pthread_getcpuclockid(thread_.native_handle(), &clock) != 0 || clock_gettime(clock, &t) != 0) return 0;
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

ServerCounters Server::counters() const noexcept {
  const Impl& i = *impl_;
  return {i.clients_now.load(), i.connections.load(), i.sent.load(),     i.sent_bytes.load(), i.dropped.load(),
          i.rejected.load(),    i.refused_ops.load(), i.closed_oversized.load(), i.pages.load()};
}

namespace {

// The access token a request presents: ?token=T or Authorization: Bearer T.
bool authorized(lws* wsi, const ServerConfig& config) noexcept {
  if (peer_is_loopback(wsi)) return true;
  if (config.token.empty()) return false;
  char buf[kTokenBytes + 16];
  const char* arg = lws_get_urlarg_by_name(wsi, "token=", buf, static_cast<int>(sizeof buf));
  if (arg != nullptr && token_matches(arg, config.token)) return true;
  const int n = lws_hdr_copy(wsi, buf, static_cast<int>(sizeof buf), WSI_TOKEN_HTTP_AUTHORIZATION);
  constexpr std::string_view kBearer = "Bearer ";
  if (n > static_cast<int>(kBearer.size()) && std::string_view(buf, kBearer.size()) == kBearer)
    return token_matches(std::string_view(buf + kBearer.size(), static_cast<std::size_t>(n) - kBearer.size()), config.token);
  return false;
}

bool offers_subprotocol(lws* wsi) noexcept {
  char buf[256];
  const int n = lws_hdr_copy(wsi, buf, static_cast<int>(sizeof buf), WSI_TOKEN_PROTOCOL);
  if (n <= 0) return false;
  std::string_view offered(buf, static_cast<std::size_t>(n));
  while (!offered.empty()) {
    const std::size_t comma = offered.find(',');
    std::string_view one = offered.substr(0, comma);
    while (!one.empty() && one.front() == ' ') one.remove_prefix(1);
    while (!one.empty() && one.back() == ' ') one.remove_suffix(1);
    if (one == kSubprotocol) return true;
    if (comma == std::string_view::npos) break;
    offered.remove_prefix(comma + 1);
  }
  return false;
}

// Whether the socket takes `size` more bytes whole. libwebsockets keeps what a send leaves over in
// memory it allocates, so the server writes only what the kernel has room for (its queue
// counted twice over, for the kernel's own overhead) and otherwise tries again shortly.
constexpr std::int64_t kRetryUs = 5'000;
bool socket_has_room(lws* wsi, std::size_t size) noexcept {
  const int fd = lws_get_socket_fd(wsi);
  int queued = 0, buffer = 0;
  socklen_t length = sizeof buffer;
  if (fd < 0 || ioctl(fd, SIOCOUTQ, &queued) != 0 || getsockopt(fd, SOL_SOCKET, SO_SNDBUF, &buffer, &length) != 0)
    return true;
  // An empty queue always takes a message: one larger than the buffer is then the library's to finish.
  return queued == 0 || static_cast<std::size_t>(queued) + 2 * (size + 16) <= static_cast<std::size_t>(buffer);
}

int refuse(lws* wsi, unsigned status, const char* why) {
  lws_return_http_status(wsi, status, why);
  return -1;
}

}  // namespace

int Server::on_event(lws* wsi, int reason_int, void* user, void* in, std::size_t len) {
  auto* connection = static_cast<Connection*>(user);
  const auto reason = static_cast<lws_callback_reasons>(reason_int);
  Client* client = connection != nullptr && connection->client > 0 ? &clients_[connection->client - 1] : nullptr;
  switch (reason) {
    case LWS_CALLBACK_HTTP:
      return serve_page(wsi, connection, in != nullptr ? static_cast<const char*>(in) : "");
    case LWS_CALLBACK_HTTP_WRITEABLE:
      if (connection == nullptr || !connection->page) break;
      return send_page(wsi, *connection);
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
      return admit(wsi);
    case LWS_CALLBACK_ESTABLISHED:
      return open_client(wsi, connection);
    case LWS_CALLBACK_CLOSED:
      if (client != nullptr) {
        client->wsi = nullptr;
        connection->client = 0;
        --impl_->clients_now;
      }
      return 0;
    case LWS_CALLBACK_RECEIVE:
      if (client == nullptr) return -1;
      return receive(wsi, *client, in, len);
    case LWS_CALLBACK_SERVER_WRITEABLE:
      if (client == nullptr) return 0;
      return send_next(wsi, *client);
    case LWS_CALLBACK_TIMER:
      lws_callback_on_writable(wsi);
      return 0;
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED:
      wake_writers();
      return 0;
    default:
      break;
  }
  return lws_callback_http_dummy(wsi, reason, user, in, len);
}

// The page's request: its headers now, the page itself as the socket takes it (send_page).
int Server::serve_page(lws* wsi, Connection* connection, std::string_view path) {
  Impl& impl = *impl_;
  if (!authorized(wsi, config_)) {
    ++impl.rejected;
    return refuse(wsi, HTTP_STATUS_UNAUTHORIZED, "access token required");
  }
  if (path != "/" && path != "/index.html") {
    ++impl.rejected;
    return refuse(wsi, HTTP_STATUS_NOT_FOUND, "not found");
  }
  unsigned char headers[LWS_PRE + 1024];
  unsigned char* start = headers + LWS_PRE;
  unsigned char* p = start;
  unsigned char* end = headers + sizeof headers - 1;
  if (lws_add_http_common_headers(wsi, HTTP_STATUS_OK, "text/html; charset=utf-8", kViewPageSize, &p, end) ||
      lws_add_http_header_by_name(wsi, reinterpret_cast<const unsigned char*>("cache-control:"),
                                  reinterpret_cast<const unsigned char*>("no-store"), 8, &p, end) ||
      lws_add_http_header_by_name(wsi, reinterpret_cast<const unsigned char*>("content-security-policy:"),
                                  reinterpret_cast<const unsigned char*>(kPagePolicy.data()),
                                  static_cast<int>(kPagePolicy.size()), &p, end) ||
      lws_finalize_write_http_header(wsi, start, &p, end))
    return 1;
  connection->page = true;
  connection->page_sent = 0;
  lws_callback_on_writable(wsi);
  return 0;
}

int Server::send_page(lws* wsi, Connection& connection) {
  Impl& impl = *impl_;
  const std::size_t chunk = std::min(kPageChunk, kViewPageSize - connection.page_sent);
  const bool last = connection.page_sent + chunk == kViewPageSize;
  std::memcpy(impl.page.data() + LWS_PRE, kViewPage + connection.page_sent, chunk);
  if (lws_write(wsi, reinterpret_cast<unsigned char*>(impl.page.data() + LWS_PRE), chunk,
                last ? LWS_WRITE_HTTP_FINAL : LWS_WRITE_HTTP) != static_cast<int>(chunk))
    return 1;
  connection.page_sent += chunk;
  if (!last) {
    lws_callback_on_writable(wsi);
    return 0;
  }
  ++impl.pages;
  connection.page = false;
  return lws_http_transaction_completed(wsi) ? -1 : 0;
}

// A WebSocket upgrade: the subprotocol, the token and a free slot, or a refusal.
int Server::admit(lws* wsi) {
  Impl& impl = *impl_;
  if (!offers_subprotocol(wsi)) {
    ++impl.rejected;
    return refuse(wsi, HTTP_STATUS_BAD_REQUEST, "the WebSocket subprotocol must be foxglove.websocket.v1");
  }
  if (!authorized(wsi, config_)) {
    ++impl.rejected;
    return refuse(wsi, HTTP_STATUS_UNAUTHORIZED, "access token required");
  }
  if (impl.clients_now.load() >= client_slots_) {
    ++impl.rejected;
    return refuse(wsi, HTTP_STATUS_SERVICE_UNAVAILABLE, "too many viewers");
  }
  return 0;
}

int Server::open_client(lws* wsi, Connection* connection) {
  Impl& impl = *impl_;
  std::size_t slot = 0;
  while (slot < client_slots_ && clients_[slot].wsi != nullptr) ++slot;
  if (slot == client_slots_) return -1;
  Client& c = clients_[slot];
  c.wsi = wsi;
  c.need_info = c.need_advertise = true;
  c.session.reset(board_->channel_count());
  c.done_seq.fill(0);
  c.sending_seq.fill(0);
  c.next_record.fill(0);
  c.subscribed_as.fill(Session::kNone);
  c.cursor = 0;
  c.rx_size = 0;
  c.refused_seen = 0;
  connection->client = static_cast<int>(slot) + 1;
  // Room for a few of the largest messages, so they seldom wait (the kernel caps this).
  if (const int fd = lws_get_socket_fd(wsi); fd >= 0) {
    std::size_t largest = 0;
    for (std::size_t ch = 0; ch < board_->channel_count(); ++ch) largest = std::max(largest, board_->spec(ch).capacity_bytes);
    const int bytes = static_cast<int>(std::min<std::size_t>(4 * largest + kControlBytes, 8u << 20));
    setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
  }
  ++impl.clients_now;
  ++impl.connections;
  lws_callback_on_writable(wsi);
  return 0;
}

// A piece of a client's message; a whole one goes to its session.
int Server::receive(lws* wsi, Client& client, const void* in, std::size_t len) {
  Impl& impl = *impl_;
  if (client.rx_size + len > client.rx.size()) {
    ++impl.closed_oversized;
    static constexpr char kWhy[] = "client messages are limited to 64 KiB";
    lws_close_reason(wsi, LWS_CLOSE_STATUS_MESSAGE_TOO_LARGE,
                     reinterpret_cast<unsigned char*>(const_cast<char*>(kWhy)), sizeof kWhy - 1);
    return -1;
  }
  std::memcpy(client.rx.data() + client.rx_size, in, len);
  client.rx_size += len;
  if (!lws_is_final_fragment(wsi) || lws_remaining_packet_payload(wsi) != 0) return 0;
  const std::size_t size = client.rx_size;
  client.rx_size = 0;
  if (lws_frame_is_binary(wsi))
    client.session.on_binary({reinterpret_cast<const std::uint8_t*>(client.rx.data()), size});
  else
    client.session.on_text({client.rx.data(), size});
  impl.refused_ops += client.session.refused() - client.refused_seen;
  client.refused_seen = client.session.refused();
  // A channel subscribed anew starts from its newest publish.
  for (std::size_t ch = 0; ch < board_->channel_count(); ++ch)
    if (client.session.subscription(ch) != client.subscribed_as[ch]) {
      client.subscribed_as[ch] = client.session.subscription(ch);
      client.done_seq[ch] = client.sending_seq[ch] = 0;
      client.next_record[ch] = 0;
    }
  lws_callback_on_writable(wsi);
  return 0;
}

// One message a time: the server's info, the advertisement, a reply, then the channels' records.
int Server::send_next(lws* wsi, Client& client) {
  Impl& impl = *impl_;
  if (client.need_info || client.need_advertise) {
    const bool info = client.need_info;
    char* text = (info ? impl.server_info.data() : impl.advertise.data()) + LWS_PRE;
    const std::size_t size = info ? impl.server_info_size : impl.advertise_size;
    if (!socket_has_room(wsi, size)) return lws_set_timer_usecs(wsi, kRetryUs), 0;
    if (lws_write(wsi, reinterpret_cast<unsigned char*>(text), size, LWS_WRITE_TEXT) < 0) return -1;
    (info ? client.need_info : client.need_advertise) = false;
    lws_callback_on_writable(wsi);
    return 0;
  }
  if (client.session.has_reply()) {
    const std::string_view reply = client.session.reply();
    if (!socket_has_room(wsi, reply.size())) return lws_set_timer_usecs(wsi, kRetryUs), 0;
    std::memcpy(impl.status.data() + LWS_PRE, reply.data(), reply.size());
    client.session.pop_reply();
    if (lws_write(wsi, reinterpret_cast<unsigned char*>(impl.status.data() + LWS_PRE), reply.size(), LWS_WRITE_TEXT) < 0)
      return -1;
    lws_callback_on_writable(wsi);
    return 0;
  }
  return send_record(wsi, client);
}

// The next record of the first subscribed channel, from the client's cursor on, with a publish
// the client has not had whole.
int Server::send_record(lws* wsi, Client& client) {
  Impl& impl = *impl_;
  const std::size_t n = board_->channel_count();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t ch = (client.cursor + k) % n;
    const std::uint32_t subscription = client.session.subscription(ch);
    if (subscription == Session::kNone) continue;
    const Publication& pub = board_->take(ch);
    if (pub.seq == 0 || pub.seq == client.done_seq[ch]) continue;
    if (pub.seq != client.sending_seq[ch]) {
      if (client.done_seq[ch] != 0 && pub.seq > client.done_seq[ch] + 1)
        impl.dropped += pub.seq - client.done_seq[ch] - 1;
      client.sending_seq[ch] = pub.seq;
      client.next_record[ch] = 0;
    }
    const std::span<char> payload = pub.payload(client.next_record[ch]);
    if (!socket_has_room(wsi, kFrameHeader + payload.size())) return lws_set_timer_usecs(wsi, kRetryUs), 0;
    char* frame = payload.data() - kFrameHeader;
    write_frame_header(std::span<char, kFrameHeader>(frame, kFrameHeader), subscription,
                       pub.records[client.next_record[ch]].stamp_ns);
    if (lws_write(wsi, reinterpret_cast<unsigned char*>(frame), kFrameHeader + payload.size(), LWS_WRITE_BINARY) < 0)
      return -1;
    ++impl.sent;
    impl.sent_bytes += kFrameHeader + payload.size();
    if (++client.next_record[ch] >= pub.record_count) {
      client.done_seq[ch] = pub.seq;
      client.cursor = ch + 1;  // the next channel goes first next time
    }
    lws_callback_on_writable(wsi);
    return 0;
  }
  return 0;
}

// After a publish: every client with a subscribed channel it has not had is asked to write.
void Server::wake_writers() {
  for (std::size_t i = 0; i < client_slots_; ++i) {
    Client& c = clients_[i];
    if (c.wsi == nullptr) continue;
    for (std::size_t ch = 0; ch < board_->channel_count(); ++ch)
      if (c.session.subscription(ch) != Session::kNone && board_->published(ch) != c.done_seq[ch]) {
        lws_callback_on_writable(c.wsi);
        break;
      }
  }
}

}  // namespace sen3bot::view
