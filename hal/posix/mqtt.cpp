// MQTT 3.1.1 through libmosquitto (Eclipse Mosquitto's own client library: TLS, last will,
// QoS 1 with its retries, keep-alive), driven from a network thread of ours with
// mosquitto_loop(), so reconnecting and the hand-over from the bounded queues stay under our
// control and the callers never block.
#include <mosquitto.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <thread>

#include "sen3bot/hal/pubsub.hpp"

namespace sen3bot::hal {

namespace {

using SteadyClock = std::chrono::steady_clock;

struct BrokerAddress {
  std::string host;
  int port = 0;
  bool tls = false;
};

Result<BrokerAddress> parse_url(std::string_view url) {
  BrokerAddress address;
  std::string_view rest;
  if (url.starts_with("mqtt://")) {
    rest = url.substr(7);
    address.port = 1883;
  } else if (url.starts_with("mqtts://")) {
    rest = url.substr(8);
    address.port = 8883;
    address.tls = true;
  } else {
    return Error::format(Errc::config, "broker '%.*s': expected mqtt://HOST[:PORT] or mqtts://HOST[:PORT]",
                         static_cast<int>(url.size()), url.data());
  }
  if (!rest.empty() && rest.back() == '/') rest.remove_suffix(1);
  const std::size_t colon = rest.rfind(':');
  if (colon != std::string_view::npos && rest.find(']') == std::string_view::npos) {
    const std::string_view port = rest.substr(colon + 1);
    int value = 0;
    for (const char c : port) {
      if (c < '0' || c > '9' || value > 65535) return Error::format(Errc::config, "broker '%.*s': bad port", static_cast<int>(url.size()), url.data());
      value = value * 10 + (c - '0');
    }
    if (port.empty() || value == 0 || value > 65535) {
      return Error::format(Errc::config, "broker '%.*s': bad port", static_cast<int>(url.size()), url.data());
    }
    address.port = value;
    rest = rest.substr(0, colon);
  }
  if (rest.empty()) return Error::format(Errc::config, "broker '%.*s': no host", static_cast<int>(url.size()), url.data());
  address.host.assign(rest);
  return address;
}

class MqttClient final : public PubSub {
 public:
  MqttClient(const PubSubOptions& options, BrokerAddress address)
      : options_(options),
        address_(std::move(address)),
        inbound_(options.inbound_slots, options.max_topic, options.max_payload),
        outbound_(options.outbound_slots, options.max_topic, options.max_payload),
        send_topic_(options.max_topic + 1),
        send_payload_(options.max_payload) {}

  ~MqttClient() override {
    close(0.0);
    if (mosq_ != nullptr) mosquitto_destroy(mosq_);
  }

  Status init() {
    static std::once_flag once;
    std::call_once(once, [] { mosquitto_lib_init(); });
    mosq_ = mosquitto_new(options_.client_id.empty() ? nullptr : options_.client_id.c_str(), true, this);
    if (mosq_ == nullptr) return Error(Errc::io, "mosquitto_new failed (out of memory or bad client id)");
    mosquitto_int_option(mosq_, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V311);
    if (!options_.username.empty()) {
      if (const int rc = mosquitto_username_pw_set(mosq_, options_.username.c_str(), options_.password.empty() ? nullptr : options_.password.c_str());
          rc != MOSQ_ERR_SUCCESS) {
        return Error::format(Errc::config, "broker credentials: %s", mosquitto_strerror(rc));
      }
    }
    if (address_.tls) {
      if (options_.ca_file.empty()) return Error(Errc::config, "an mqtts:// broker needs a CA file to verify it against");
      const char* cert = options_.cert_file.empty() ? nullptr : options_.cert_file.c_str();
      const char* key = options_.key_file.empty() ? nullptr : options_.key_file.c_str();
      if (const int rc = mosquitto_tls_set(mosq_, options_.ca_file.c_str(), nullptr, cert, key, nullptr); rc != MOSQ_ERR_SUCCESS) {
        return Error::format(Errc::config, "TLS set-up (CA '%s'): %s", options_.ca_file.c_str(), mosquitto_strerror(rc));
      }
    }
    if (options_.will) {
      const PubSubWill& will = *options_.will;
      if (const int rc = mosquitto_will_set(mosq_, will.topic.c_str(), static_cast<int>(will.payload.size()), will.payload.data(), will.qos,
                                            will.retain);
          rc != MOSQ_ERR_SUCCESS) {
        return Error::format(Errc::config, "last will on '%s': %s", will.topic.c_str(), mosquitto_strerror(rc));
      }
    }
    for (const PubSubSubscription& sub : options_.subscriptions) {
      if (!valid_topic_filter(sub.filter)) return Error::format(Errc::config, "bad topic filter '%s'", sub.filter.c_str());
    }
    mosquitto_max_inflight_messages_set(mosq_, static_cast<unsigned>(std::max<std::size_t>(options_.max_inflight, 1)));
    mosquitto_connect_callback_set(mosq_, &MqttClient::on_connect);
    mosquitto_disconnect_callback_set(mosq_, &MqttClient::on_disconnect);
    mosquitto_message_callback_set(mosq_, &MqttClient::on_message);
    mosquitto_publish_callback_set(mosq_, &MqttClient::on_publish);
    thread_ = std::thread([this] { run(); });
    return Status::success();
  }

  Status publish(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retain) override {
    return queue_publish(outbound_, counters_, closing_.load(), topic, payload, qos, retain);
  }

  Result<std::optional<PubSubMessage>> receive(std::span<char> topic, std::span<std::uint8_t> payload) override {
    return inbound_.pop(topic, payload);
  }
  [[nodiscard]] PubSubState state() const noexcept override { return state_.load(); }
  [[nodiscard]] std::uint32_t session() const noexcept override { return counters_.sessions.load(); }
  [[nodiscard]] PubSubStats stats() const noexcept override { return counters_.snapshot(); }

  void close(double timeout_s) noexcept override {
    if (!thread_.joinable()) return;
    close_timeout_s_.store(timeout_s);
    closing_.store(true);
    thread_.join();
    state_.store(PubSubState::closed);
  }

 private:
  static MqttClient& self(void* user) { return *static_cast<MqttClient*>(user); }

  static void on_connect(mosquitto* mosq, void* user, int rc) {
    MqttClient& client = self(user);
    if (rc != 0) {
      client.counters_.connections_refused.fetch_add(1);
      std::fprintf(stderr, "mqtt: %s:%d refused the connection: %s\n", client.address_.host.c_str(), client.address_.port,
                   mosquitto_connack_string(rc));
      return;  // the broker closes the socket; the loop sees it and backs off
    }
    for (const PubSubSubscription& sub : client.options_.subscriptions) {
      mosquitto_subscribe(mosq, nullptr, sub.filter.c_str(), sub.qos);
    }
    client.backoff_s_ = client.options_.reconnect_min_s;
    client.state_.store(PubSubState::connected);
    client.counters_.sessions.fetch_add(1);
  }

  static void on_disconnect(mosquitto*, void* user, int) {
    MqttClient& client = self(user);
    if (client.state_.load() == PubSubState::connected) client.counters_.connection_losses.fetch_add(1);
    client.state_.store(PubSubState::disconnected);
  }

  static void on_message(mosquitto*, void* user, const mosquitto_message* message) {
    MqttClient& client = self(user);
    const std::string_view topic = message->topic != nullptr ? std::string_view(message->topic) : std::string_view();
    const std::size_t size = message->payloadlen > 0 ? static_cast<std::size_t>(message->payloadlen) : 0;
    if (topic.size() > client.options_.max_topic || size > client.options_.max_payload) {
      client.counters_.receive_oversized.fetch_add(1);
      return;
    }
    if (!client.inbound_.push(topic, {static_cast<const std::uint8_t*>(message->payload), size}, message->qos, message->retain)) {
      client.counters_.receive_dropped.fetch_add(1);
      return;
    }
    client.counters_.received.fetch_add(1);
  }

  static void on_publish(mosquitto*, void* user, int) {
    MqttClient& client = self(user);
    client.counters_.published.fetch_add(1);
    if (client.inflight_ > 0) --client.inflight_;
  }

  // Hands queued messages to libmosquitto while fewer than max_inflight are outstanding.
  void send_queued() {
    while (state_.load() == PubSubState::connected && inflight_ < options_.max_inflight) {
      auto message = outbound_.pop({send_topic_.data(), options_.max_topic}, send_payload_);
      if (!message || !message.value()) return;
      const PubSubMessage& m = *message.value();
      send_topic_[m.topic_size] = '\0';
      const int rc = mosquitto_publish(mosq_, nullptr, send_topic_.data(), static_cast<int>(m.payload_size), send_payload_.data(), m.qos, m.retained);
      if (rc != MOSQ_ERR_SUCCESS) {
        counters_.publish_dropped.fetch_add(1);  // the connection went while sending: the loop will notice
        return;
      }
      ++inflight_;
    }
  }

  void run() {
    bool ever_connected_socket = false;
    bool socket_open = false;
    SteadyClock::time_point next_attempt = SteadyClock::now();
    SteadyClock::time_point close_deadline{};
    bool closing_seen = false;
    backoff_s_ = options_.reconnect_min_s;
    for (;;) {
      const auto now = SteadyClock::now();
      if (closing_.load() && !closing_seen) {
        closing_seen = true;
        close_deadline = now + std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(close_timeout_s_.load()));
      }
      if (closing_seen) {
        const bool drained = outbound_.size() == 0 && inflight_ == 0;
        if (drained || now >= close_deadline || state_.load() != PubSubState::connected) {
          if (state_.load() == PubSubState::connected) {
            mosquitto_disconnect(mosq_);  // a clean DISCONNECT: no last will
            for (int i = 0; i < 10 && mosquitto_loop(mosq_, 10, 1) == MOSQ_ERR_SUCCESS; ++i) {
            }
          }
          return;
        }
      }
      if (socket_open) {
        send_queued();
        const int rc = mosquitto_loop(mosq_, outbound_.size() > 0 && inflight_ < options_.max_inflight ? 0 : 10, 1);
        if (rc != MOSQ_ERR_SUCCESS) {
          socket_open = false;
          if (state_.load() == PubSubState::connected) counters_.connection_losses.fetch_add(1);
          state_.store(PubSubState::disconnected);
          inflight_ = 0;  // libmosquitto resends its unacknowledged QoS 1 messages itself on reconnect
          next_attempt = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(backoff_s_));
          backoff_s_ = std::min(backoff_s_ * 2, options_.reconnect_max_s);
        }
        continue;
      }
      if (closing_seen) return;
      if (now < next_attempt) {
        std::this_thread::sleep_for(std::min<SteadyClock::duration>(next_attempt - now, std::chrono::milliseconds(20)));
        continue;
      }
      state_.store(PubSubState::connecting);
      // Asynchronous: the TCP connect completes in the loop, so an unreachable broker cannot
      // hold this thread (and close()) for the kernel's connect timeout.
      const int rc = ever_connected_socket ? mosquitto_reconnect_async(mosq_)
                                           : mosquitto_connect_async(mosq_, address_.host.c_str(), address_.port, options_.keepalive_s);
      if (rc == MOSQ_ERR_SUCCESS) {
        ever_connected_socket = true;
        socket_open = true;
      } else {
        if (rc != last_connect_error_)
          std::fprintf(stderr, "mqtt: connecting to %s:%d: %s\n", address_.host.c_str(), address_.port,
                       rc == MOSQ_ERR_ERRNO ? std::strerror(errno) : mosquitto_strerror(rc));
        last_connect_error_ = rc;
        state_.store(PubSubState::disconnected);
        next_attempt = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(backoff_s_));
        backoff_s_ = std::min(backoff_s_ * 2, options_.reconnect_max_s);
      }
    }
  }

  PubSubOptions options_;
  BrokerAddress address_;
  mosquitto* mosq_ = nullptr;
  MessageQueue inbound_;
  MessageQueue outbound_;
  std::vector<char> send_topic_;
  std::vector<std::uint8_t> send_payload_;
  std::thread thread_;
  std::atomic<bool> closing_{false};
  std::atomic<double> close_timeout_s_{1.0};
  std::size_t inflight_ = 0;  // the network thread's own
  int last_connect_error_ = MOSQ_ERR_SUCCESS;  // reported once until it changes
  double backoff_s_ = 0.5;    // the network thread's own
  std::atomic<PubSubState> state_{PubSubState::connecting};
  PubSubCounters counters_;
};

}  // namespace

Result<std::unique_ptr<PubSub>> open_mqtt(const PubSubOptions& options) {
  auto address = parse_url(options.url);
  if (!address) return address.error();
  if (options.max_topic == 0 || options.max_payload == 0) return Error(Errc::config, "mqtt: zero-sized topic or payload limit");
  // libmosquitto refuses to connect with less, and would only say so on every attempt.
  if (options.keepalive_s < 5) return Error::format(Errc::config, "mqtt: keepalive_s %d: at least 5 s", options.keepalive_s);
  auto client = std::make_unique<MqttClient>(options, std::move(address.value()));
  if (Status status = client->init(); !status) return status.error();
  return std::unique_ptr<PubSub>(std::move(client));
}

}  // namespace sen3bot::hal
