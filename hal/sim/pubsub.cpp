// Topic rules, the bounded message queue, and the in-process broker.
#include "sen3bot/hal/pubsub.hpp"

#include <algorithm>
#include <cstring>

namespace sen3bot::hal {

const char* to_string(PubSubState state) noexcept {
  switch (state) {
    case PubSubState::connecting: return "connecting";
    case PubSubState::connected: return "connected";
    case PubSubState::disconnected: return "disconnected";
    case PubSubState::closed: return "closed";
  }
  return "closed";
}

namespace {

// The next level of a topic or filter at pos, and pos moved past its '/' (npos at the end).
std::string_view next_level(std::string_view text, std::size_t& pos) noexcept {
  const std::size_t slash = text.find('/', pos);
  std::string_view level;
  if (slash == std::string_view::npos) {
    level = text.substr(pos);
    pos = std::string_view::npos;
  } else {
    level = text.substr(pos, slash - pos);
    pos = slash + 1;
  }
  return level;
}

}  // namespace

bool topic_matches(std::string_view filter, std::string_view topic) noexcept {
  if (filter.empty() || topic.empty()) return false;
  if (topic.front() == '$' && (filter.front() == '+' || filter.front() == '#')) return false;
  std::size_t f = 0;
  std::size_t t = 0;
  while (f != std::string_view::npos) {
    const std::string_view want = next_level(filter, f);
    if (want == "#") return true;  // matches the parent level too ("a/#" matches "a")
    if (t == std::string_view::npos) return false;
    const std::string_view have = next_level(topic, t);
    if (want != "+" && want != have) return false;
  }
  return t == std::string_view::npos;
}

bool valid_publish_topic(std::string_view topic, std::size_t max_size) noexcept {
  if (topic.empty() || topic.size() > max_size) return false;
  return topic.find_first_of(std::string_view("+#\0", 3)) == std::string_view::npos;
}

bool valid_topic_filter(std::string_view filter) noexcept {
  if (filter.empty() || filter.find('\0') != std::string_view::npos) return false;
  std::size_t pos = 0;
  while (pos != std::string_view::npos) {
    const std::string_view level = next_level(filter, pos);
    const bool wild = level.find_first_of("+#") != std::string_view::npos;
    if (wild && level != "+" && level != "#") return false;
    if (level == "#" && pos != std::string_view::npos) return false;
  }
  return true;
}

MessageQueue::MessageQueue(std::size_t slots, std::size_t max_topic, std::size_t max_payload)
    : max_topic_(max_topic),
      max_payload_(max_payload),
      slots_(std::max<std::size_t>(slots, 1)),
      topics_(slots_.size() * max_topic),
      payloads_(slots_.size() * max_payload) {}

bool MessageQueue::push(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retained) {
  if (topic.size() > max_topic_ || payload.size() > max_payload_) return false;
  const std::lock_guard lock(mutex_);
  if (count_ == slots_.size()) return false;
  const std::size_t index = (head_ + count_) % slots_.size();
  Slot& slot = slots_[index];
  slot.topic_size = topic.size();
  slot.payload_size = payload.size();
  slot.qos = qos;
  slot.retained = retained;
  if (!topic.empty()) std::memcpy(topics_.data() + index * max_topic_, topic.data(), topic.size());
  if (!payload.empty()) std::memcpy(payloads_.data() + index * max_payload_, payload.data(), payload.size());
  ++count_;
  return true;
}

Result<std::optional<PubSubMessage>> MessageQueue::pop(std::span<char> topic, std::span<std::uint8_t> payload) {
  const std::lock_guard lock(mutex_);
  if (count_ == 0) return std::optional<PubSubMessage>{};
  const Slot& slot = slots_[head_];
  if (slot.topic_size > topic.size() || slot.payload_size > payload.size()) {
    return Error::format(Errc::capacity, "a queued message (%zu-byte topic, %zu-byte payload) does not fit the buffers given",
                         slot.topic_size, slot.payload_size);
  }
  if (slot.topic_size != 0) std::memcpy(topic.data(), topics_.data() + head_ * max_topic_, slot.topic_size);
  if (slot.payload_size != 0) std::memcpy(payload.data(), payloads_.data() + head_ * max_payload_, slot.payload_size);
  const PubSubMessage message{slot.topic_size, slot.payload_size, slot.qos, slot.retained};
  head_ = (head_ + 1) % slots_.size();
  --count_;
  return std::optional<PubSubMessage>{message};
}

Status queue_publish(MessageQueue& queue, PubSubCounters& counters, bool closed, std::string_view topic,
                     std::span<const std::uint8_t> payload, int qos, bool retain) noexcept {
  if (closed || !valid_publish_topic(topic, queue.max_topic()) || payload.size() > queue.max_payload() || qos < 0 || qos > 1) {
    counters.publish_refused.fetch_add(1);
    return Error::format(Errc::invalid_argument, "publish refused: topic '%.*s', %zu bytes, qos %d",
                         static_cast<int>(std::min<std::size_t>(topic.size(), 80)), topic.data(), payload.size(), qos);
  }
  if (!queue.push(topic, payload, qos, retain)) {
    counters.publish_dropped.fetch_add(1);
    return Error(Errc::capacity, "publish dropped: the outbound queue is full");
  }
  return Status::success();
}

std::size_t MessageQueue::size() const {
  const std::lock_guard lock(mutex_);
  return count_;
}

// ----------------------------------------------------------------------------------------------
// The in-process broker. One mutex guards the whole broker: delivery copies into the receiving
// clients' inbound queues (each with its own lock, always taken after the broker's).

namespace {
class MemoryClient;
}

class MemoryBroker::Impl {
 public:
  explicit Impl(const Limits& limits)
      : limits_(limits), records_(limits.max_clients), retained_(limits.max_retained) {
    for (Record& record : records_) record.subscriptions.reserve(limits.max_subscriptions);
    for (Retained& slot : retained_) {
      slot.topic.reserve(limits.max_topic);
      slot.payload.reserve(limits.max_retained_payload);
    }
  }

  struct Record {
    MemoryClient* client = nullptr;
    std::string id;
    std::vector<PubSubSubscription> subscriptions;
    bool reachable = true;
  };
  struct Retained {
    bool used = false;
    std::string topic;
    std::vector<std::uint8_t> payload;
  };

  Result<std::unique_ptr<PubSub>> connect(const PubSubOptions& options);
  void detach(MemoryClient& client, bool publish_will);
  void set_reachable(std::string_view client_id, bool reachable);
  // Routes one message to every reachable subscriber; with retain, keeps (or with an empty
  // payload, clears) the topic's retained message. Called with mutex_ held.
  void route(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retain);
  // Sends a client's queued publishes and its subscriptions' retained messages. mutex_ held.
  void on_connected(Record& record);

  std::mutex mutex_;
  Limits limits_;
  std::vector<Record> records_;
  std::vector<Retained> retained_;
  std::uint64_t routed_ = 0;
  std::uint64_t dropped_ = 0;
};

namespace {

class MemoryClient final : public PubSub {
 public:
  MemoryClient(MemoryBroker::Impl& broker, const PubSubOptions& options)
      : broker_(broker),
        options_(options),
        inbound_(options.inbound_slots, options.max_topic, options.max_payload),
        outbound_(options.outbound_slots, options.max_topic, options.max_payload),
        scratch_topic_(options.max_topic),
        scratch_payload_(options.max_payload) {}
  ~MemoryClient() override {
    // Gone without a clean close: a crashed process, so the broker publishes the will.
    if (state_.load() != PubSubState::closed) broker_.detach(*this, true);
  }

  Status publish(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retain) override {
    if (Status queued = queue_publish(outbound_, counters_, state_.load() == PubSubState::closed, topic, payload, qos, retain);
        !queued)
      return queued;
    const std::lock_guard lock(broker_.mutex_);
    if (record_ != nullptr && record_->reachable) flush_locked();
    return Status::success();
  }

  Result<std::optional<PubSubMessage>> receive(std::span<char> topic, std::span<std::uint8_t> payload) override {
    return inbound_.pop(topic, payload);
  }
  [[nodiscard]] PubSubState state() const noexcept override { return state_.load(); }
  [[nodiscard]] std::uint32_t session() const noexcept override { return counters_.sessions.load(); }
  [[nodiscard]] PubSubStats stats() const noexcept override { return counters_.snapshot(); }
  void close(double) noexcept override {
    if (state_.load() == PubSubState::closed) return;
    {
      const std::lock_guard lock(broker_.mutex_);
      if (record_ != nullptr && record_->reachable) flush_locked();
    }
    broker_.detach(*this, false);
  }

  // Broker side, with the broker's mutex held.
  void deliver(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retained) {
    if (topic.size() > options_.max_topic || payload.size() > options_.max_payload) {
      counters_.receive_oversized.fetch_add(1);
      ++broker_.dropped_;
    } else if (!inbound_.push(topic, payload, qos, retained)) {
      counters_.receive_dropped.fetch_add(1);
      ++broker_.dropped_;
    } else {
      counters_.received.fetch_add(1);
    }
  }
  void flush_locked() {
    for (;;) {
      auto message = outbound_.pop(scratch_topic_, scratch_payload_);
      if (!message || !message.value()) return;
      const PubSubMessage& m = *message.value();
      broker_.route({scratch_topic_.data(), m.topic_size}, {scratch_payload_.data(), m.payload_size}, m.qos, m.retained);
      counters_.published.fetch_add(1);
    }
  }
  void set_connected(MemoryBroker::Impl::Record* record) {
    record_ = record;
    state_.store(PubSubState::connected);
    counters_.sessions.fetch_add(1);
  }
  void set_cut_off() {
    state_.store(PubSubState::disconnected);
    counters_.connection_losses.fetch_add(1);
  }
  void set_closed() {
    record_ = nullptr;
    state_.store(PubSubState::closed);
  }
  [[nodiscard]] const PubSubOptions& options() const noexcept { return options_; }

 private:
  MemoryBroker::Impl& broker_;
  PubSubOptions options_;
  MessageQueue inbound_;
  MessageQueue outbound_;
  std::vector<char> scratch_topic_;
  std::vector<std::uint8_t> scratch_payload_;
  MemoryBroker::Impl::Record* record_ = nullptr;  // guarded by the broker's mutex
  std::atomic<PubSubState> state_{PubSubState::connecting};
  PubSubCounters counters_;
};

}  // namespace

Result<std::unique_ptr<PubSub>> MemoryBroker::Impl::connect(const PubSubOptions& options) {
  if (options.client_id.empty()) return Error(Errc::invalid_argument, "an in-process broker client needs a client id");
  if (options.subscriptions.size() > limits_.max_subscriptions) {
    return Error::format(Errc::capacity, "%zu subscriptions, the broker keeps %zu per client", options.subscriptions.size(),
                         limits_.max_subscriptions);
  }
  for (const PubSubSubscription& sub : options.subscriptions) {
    if (!valid_topic_filter(sub.filter)) return Error::format(Errc::invalid_argument, "bad topic filter '%s'", sub.filter.c_str());
  }
  auto client = std::make_unique<MemoryClient>(*this, options);
  const std::lock_guard lock(mutex_);
  Record* free_record = nullptr;
  for (Record& record : records_) {
    if (record.client != nullptr && record.id == options.client_id) {
      return Error::format(Errc::invalid_argument, "client id '%s' is already connected", options.client_id.c_str());
    }
    if (record.client == nullptr && free_record == nullptr) free_record = &record;
  }
  if (free_record == nullptr) return Error::format(Errc::capacity, "the broker holds %zu clients", limits_.max_clients);
  free_record->client = client.get();
  free_record->id = options.client_id;
  free_record->subscriptions.assign(options.subscriptions.begin(), options.subscriptions.end());
  free_record->reachable = true;
  client->set_connected(free_record);
  on_connected(*free_record);
  return std::unique_ptr<PubSub>(std::move(client));
}

void MemoryBroker::Impl::on_connected(Record& record) {
  for (const PubSubSubscription& sub : record.subscriptions) {
    for (const Retained& slot : retained_) {
      if (slot.used && topic_matches(sub.filter, slot.topic)) record.client->deliver(slot.topic, slot.payload, sub.qos, true);
    }
  }
  record.client->flush_locked();
}

void MemoryBroker::Impl::detach(MemoryClient& client, bool publish_will) {
  const std::lock_guard lock(mutex_);
  for (Record& record : records_) {
    if (record.client != &client) continue;
    const bool was_reachable = record.reachable;
    record.client = nullptr;
    record.id.clear();
    record.subscriptions.clear();
    client.set_closed();
    // A client already cut off had its will published then.
    if (publish_will && was_reachable && client.options().will) {
      const PubSubWill& will = *client.options().will;
      route(will.topic, {reinterpret_cast<const std::uint8_t*>(will.payload.data()), will.payload.size()}, will.qos, will.retain);
    }
    return;
  }
  client.set_closed();
}

void MemoryBroker::Impl::set_reachable(std::string_view client_id, bool reachable) {
  const std::lock_guard lock(mutex_);
  for (Record& record : records_) {
    if (record.client == nullptr || record.id != client_id || record.reachable == reachable) continue;
    record.reachable = reachable;
    if (!reachable) {
      record.client->set_cut_off();
      if (const auto& will = record.client->options().will) {
        route(will->topic, {reinterpret_cast<const std::uint8_t*>(will->payload.data()), will->payload.size()}, will->qos, will->retain);
      }
    } else {
      record.client->set_connected(&record);
      on_connected(record);
    }
  }
}

void MemoryBroker::Impl::route(std::string_view topic, std::span<const std::uint8_t> payload, int qos, bool retain) {
  ++routed_;
  if (retain) {
    Retained* slot = nullptr;
    Retained* free_slot = nullptr;
    for (Retained& candidate : retained_) {
      if (candidate.used && candidate.topic == topic) slot = &candidate;
      if (!candidate.used && free_slot == nullptr) free_slot = &candidate;
    }
    if (payload.empty()) {
      if (slot != nullptr) slot->used = false;  // an empty retained message clears the topic
    } else if (topic.size() > limits_.max_topic || payload.size() > limits_.max_retained_payload) {
      ++dropped_;  // delivered below, but not kept
    } else if (slot != nullptr || free_slot != nullptr) {
      Retained& target = slot != nullptr ? *slot : *free_slot;
      target.used = true;
      target.topic.assign(topic);
      target.payload.assign(payload.begin(), payload.end());
    } else {
      ++dropped_;
    }
  }
  for (Record& record : records_) {
    if (record.client == nullptr || !record.reachable) continue;
    for (const PubSubSubscription& sub : record.subscriptions) {
      if (topic_matches(sub.filter, topic)) {
        // A message retained on publish goes to current subscribers as a normal one (MQTT 3.3.1.3).
        record.client->deliver(topic, payload, std::min(qos, sub.qos), false);
        break;
      }
    }
  }
}

MemoryBroker::MemoryBroker() : MemoryBroker(Limits{}) {}
MemoryBroker::MemoryBroker(const Limits& limits) : impl_(std::make_unique<Impl>(limits)) {}
MemoryBroker::~MemoryBroker() = default;

Result<std::unique_ptr<PubSub>> MemoryBroker::connect(const PubSubOptions& options) { return impl_->connect(options); }

void MemoryBroker::set_reachable(std::string_view client_id, bool reachable) { impl_->set_reachable(client_id, reachable); }

void MemoryBroker::publish(std::string_view topic, std::span<const std::uint8_t> payload, bool retain) {
  const std::lock_guard lock(impl_->mutex_);
  impl_->route(topic, payload, 1, retain);
}

std::uint64_t MemoryBroker::messages_routed() const noexcept {
  const std::lock_guard lock(impl_->mutex_);
  return impl_->routed_;
}

std::uint64_t MemoryBroker::deliveries_dropped() const noexcept {
  const std::lock_guard lock(impl_->mutex_);
  return impl_->dropped_;
}

}  // namespace sen3bot::hal
