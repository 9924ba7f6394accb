#pragma once
// Publish/subscribe messaging with MQTT semantics (topics, QoS 0/1, retained messages, a last
// will): the fleet's link. The robot computer speaks MQTT 3.1.1 to a broker through libmosquitto
// (hal/posix/mqtt.cpp); the simulated board hands out clients of an in-process broker
// (MemoryBroker, below), so several simulated robots and the fleet's centre can share one site
// in lockstep.
//
// The caller's side never blocks and never allocates: publish() copies into a bounded outbound
// queue and receive() copies out of a bounded inbound queue, both sized at open. The network
// side (a thread of the client's own, or the in-process broker) does the rest.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

enum class PubSubState : std::uint8_t { connecting, connected, disconnected, closed };
[[nodiscard]] const char* to_string(PubSubState state) noexcept;

struct PubSubWill {
  std::string topic;
  std::string payload;
  int qos = 1;
  bool retain = true;
};

struct PubSubSubscription {
  std::string filter;  // an MQTT topic filter: '+' one level, '#' the rest
  int qos = 0;
};

struct PubSubOptions {
  // "mqtt://HOST[:PORT]" (1883), "mqtts://HOST[:PORT]" (8883, TLS), or a name the board knows
  // ("sim").
  std::string url;
  std::string client_id;
  std::string username;  // empty: no credentials
  std::string password;
  std::string ca_file;    // mqtts: the CA that signed the broker's certificate (required)
  std::string cert_file;  // mqtts: a client certificate (optional, with key_file)
  std::string key_file;
  int keepalive_s = 15;   // the broker declares the client lost after 1.5 times this
  std::optional<PubSubWill> will;
  std::vector<PubSubSubscription> subscriptions;  // made again on every (re)connect
  std::size_t max_topic = 256;         // bytes; longer topics are refused, never truncated
  std::size_t max_payload = 64 * 1024; // bytes, each way
  std::size_t inbound_slots = 16;
  std::size_t outbound_slots = 32;
  std::size_t max_inflight = 16;       // QoS 1 messages handed to the network and not yet acknowledged
  double reconnect_min_s = 0.5;        // backoff after a lost or refused connection, doubling
  double reconnect_max_s = 8.0;
};

// A message as the caller's buffers hold it after receive().
struct PubSubMessage {
  std::size_t topic_size = 0;
  std::size_t payload_size = 0;
  int qos = 0;
  bool retained = false;
};

struct PubSubStats {
  std::uint64_t published = 0;           // taken by the network (QoS 1: acknowledged)
  std::uint64_t publish_dropped = 0;     // refused: the outbound queue was full
  std::uint64_t publish_refused = 0;     // refused: too large, a bad topic, or closed
  std::uint64_t received = 0;
  std::uint64_t receive_dropped = 0;     // the inbound queue was full
  std::uint64_t receive_oversized = 0;   // larger than max_payload or max_topic
  std::uint64_t connects = 0;            // successful connections, the first one included
  std::uint64_t connection_losses = 0;
  std::uint64_t connections_refused = 0; // the broker said no (credentials, identifier)
};

// The counters a link keeps, bumped from any thread; stats() is their snapshot.
struct PubSubCounters {
  std::atomic<std::uint64_t> published{0}, publish_dropped{0}, publish_refused{0}, received{0}, receive_dropped{0},
      receive_oversized{0}, connection_losses{0}, connections_refused{0};
  std::atomic<std::uint32_t> sessions{0};
  [[nodiscard]] PubSubStats snapshot() const noexcept {
    PubSubStats s;
    s.published = published.load();
    s.publish_dropped = publish_dropped.load();
    s.publish_refused = publish_refused.load();
    s.received = received.load();
    s.receive_dropped = receive_dropped.load();
    s.receive_oversized = receive_oversized.load();
    s.connects = sessions.load();
    s.connection_losses = connection_losses.load();
    s.connections_refused = connections_refused.load();
    return s;
  }
};

// A payload given as text.
[[nodiscard]] inline std::span<const std::uint8_t> as_bytes(std::string_view text) noexcept {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

class PubSub {
 public:
  virtual ~PubSub() = default;
  // Queues one message. Errc::capacity when the outbound queue is full (the caller decides what
  // to drop; state messages are simply sent again later), Errc::invalid_argument for a payload
  // or topic over the limits or a topic with wildcards. Queued messages wait for a connection.
  virtual Status publish(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retain) = 0;
  // Copies the oldest received message into the buffers (sized max_topic and max_payload at
  // least), or nullopt when none waits.
  virtual Result<std::optional<PubSubMessage>> receive(std::span<char> topic, std::span<std::uint8_t> payload) = 0;
  [[nodiscard]] virtual PubSubState state() const noexcept = 0;
  // Increments on every successful connection: a caller that sees it change sends what a
  // fresh session needs (its online message, its state).
  [[nodiscard]] virtual std::uint32_t session() const noexcept = 0;
  [[nodiscard]] virtual PubSubStats stats() const noexcept = 0;
  // Sends what is queued (waiting up to timeout_s for the broker to take it), then disconnects
  // cleanly: the broker does not publish the last will. Further publishes are refused.
  virtual void close(double timeout_s = 1.0) noexcept = 0;
};

// True when an MQTT topic filter matches a topic (MQTT 3.1.1 section 4.7): '+' matches one
// level, a trailing '#' the parent level and everything below it; filters starting with a
// wildcard do not match topics starting with '$'.
[[nodiscard]] bool topic_matches(std::string_view filter, std::string_view topic) noexcept;
// A topic a client may publish to: not empty, no wildcard, no NUL, at most max_size bytes.
[[nodiscard]] bool valid_publish_topic(std::string_view topic, std::size_t max_size) noexcept;
// A filter a client may subscribe with: '+' and '#' only as whole levels, '#' last.
[[nodiscard]] bool valid_topic_filter(std::string_view filter) noexcept;

class MessageQueue;
// What every link does with a publish: refuse it (counted, Errc::invalid_argument) when the link
// is closed or the topic, size or QoS is not allowed, else queue it (Errc::capacity, counted,
// when the queue is full).
Status queue_publish(MessageQueue& queue, PubSubCounters& counters, bool closed, std::string_view topic,
                     std::span<const std::uint8_t> payload, int qos, bool retain) noexcept;

// A bounded queue of messages in memory allocated once (slots x (max_topic + max_payload)).
// Thread-safe for one or more producers and consumers; every call is O(size of one message).
class MessageQueue {
 public:
  MessageQueue(std::size_t slots, std::size_t max_topic, std::size_t max_payload);
  // False when full or when topic/payload exceed the slot.
  bool push(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retained);
  // Copies the oldest message out; nullopt when empty. Errc::capacity when the caller's buffers
  // are too small (the message stays queued).
  Result<std::optional<PubSubMessage>> pop(std::span<char> topic, std::span<std::uint8_t> payload);
  [[nodiscard]] std::size_t size() const;
  [[nodiscard]] std::size_t max_topic() const noexcept { return max_topic_; }
  [[nodiscard]] std::size_t max_payload() const noexcept { return max_payload_; }

 private:
  struct Slot {
    std::size_t topic_size = 0;
    std::size_t payload_size = 0;
    int qos = 0;
    bool retained = false;
  };
  std::size_t max_topic_;
  std::size_t max_payload_;
  std::vector<Slot> slots_;
  std::vector<char> topics_;
  std::vector<std::uint8_t> payloads_;
  std::size_t head_ = 0;
  std::size_t count_ = 0;
  mutable std::mutex mutex_;
};

// An MQTT client through libmosquitto, with a network thread of its own that connects,
// subscribes, reconnects with backoff, and moves messages between the queues and the socket.
// Allocates at open; libmosquitto allocates on its thread per message, bounded by max_inflight.
Result<std::unique_ptr<PubSub>> open_mqtt(const PubSubOptions& options);

// An in-process broker with MQTT semantics, for simulation and tests: topic filters, retained
// messages, QoS 0 and 1 (delivery is immediate and lossless unless a client's inbound queue is
// full, which is counted), last wills published when a client is cut off (not on close()),
// and a switch that cuts a client off the broker and lets it back. Fixed memory: clients,
// subscriptions and retained messages are bounded at construction.
class MemoryBroker {
 public:
  struct Limits {
    std::size_t max_clients = 64;
    std::size_t max_subscriptions = 16;  // per client
    std::size_t max_retained = 128;
    std::size_t max_topic = 256;
    std::size_t max_retained_payload = 16 * 1024;  // retained: connection and factsheet messages
  };
  MemoryBroker();
  explicit MemoryBroker(const Limits& limits);
  ~MemoryBroker();
  MemoryBroker(const MemoryBroker&) = delete;
  MemoryBroker& operator=(const MemoryBroker&) = delete;

  // A client of this broker; it outlives none of them. Its options' url is ignored and the
  // credentials are not checked (the real broker's ACL is tested against Mosquitto).
  // Errc::capacity past max_clients, Errc::invalid_argument for a client id already connected.
  Result<std::unique_ptr<PubSub>> connect(const PubSubOptions& options);
  // Cuts a client off as a lost network would: its will is published, its publishes are
  // refused (counted as dropped) until reachable again, then it reconnects and subscribes anew.
  void set_reachable(std::string_view client_id, bool reachable);
  // A message from outside any client (a test's master control).
  void publish(std::string_view topic, std::span<const std::uint8_t> payload, bool retain);
  [[nodiscard]] std::uint64_t messages_routed() const noexcept;
  [[nodiscard]] std::uint64_t deliveries_dropped() const noexcept;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace sen3bot::hal
