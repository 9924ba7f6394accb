#include "sen3bot/view/session.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace sen3bot::view {

namespace {

// Operations of the subprotocol that need a capability this server does not announce.
constexpr std::array<std::string_view, 11> kReadOnlyOps = {
    "advertise",       "unadvertise",        "publish",
    "getParameters",   "setParameters",      "subscribeParameterUpdates",
    "unsubscribeParameterUpdates", "subscribeConnectionGraph", "unsubscribeConnectionGraph",
    "fetchAsset",      "callService",
};

Result<std::string_view> finished(const json::Writer& w) noexcept { return w.finish(); }

// The text of a JSON string value, cut to fit a status message.
std::string_view short_text(const json::Value& v, std::span<char> buf) noexcept {
  if (!v.is(json::Type::string)) return "?";
  auto n = v.string(buf);
  return n ? std::string_view(buf.data(), *n) : std::string_view("(too long)");
}

}  // namespace

Result<std::string_view> write_server_info(std::span<char> out, std::string_view name, std::string_view session_id) noexcept {
  json::Writer w(out);
  w.begin_object().member("op", "serverInfo").member("name", name);
  w.key("capabilities").begin_array().end_array();
  w.key("supportedEncodings").begin_array().end_array();
  w.key("metadata").begin_object().member("access", "read-only").end_object();
  w.member("sessionId", session_id);
  w.end_object();
  return finished(w);
}

Result<std::string_view> write_advertise(std::span<char> out, const ChannelBoard& board) noexcept {
  json::Writer w(out);
  w.begin_object().member("op", "advertise").key("channels").begin_array();
  for (std::size_t i = 0; i < board.channel_count(); ++i) {
    const ChannelSpec& c = board.spec(i);
    w.begin_object()
        .member_uint32("id", static_cast<std::uint32_t>(i))
        .member("topic", c.topic)
        .member("encoding", "json")
        .member("schemaName", schema_name(c.schema))
        .member("schema", json_schema(c.schema))
        .member("schemaEncoding", "jsonschema")
        .end_object();
  }
  w.end_array().end_object();
  return finished(w);
}

Result<std::string_view> write_status(std::span<char> out, StatusLevel level, std::string_view message) noexcept {
  json::Writer w(out);
  w.begin_object().member("op", "status").member_uint32("level", static_cast<std::uint32_t>(level));
  w.member("message", message).end_object();
  return finished(w);
}

void write_frame_header(std::span<char, kFrameHeader> out, std::uint32_t subscription_id, hal::Nanos stamp_ns) noexcept {
  const std::uint64_t stamp = stamp_ns > 0 ? static_cast<std::uint64_t>(stamp_ns) : 0;
  out[0] = static_cast<char>(kOpMessageData);
  for (int i = 0; i < 4; ++i) out[1 + i] = static_cast<char>((subscription_id >> (8 * i)) & 0xffu);
  for (int i = 0; i < 8; ++i) out[5 + i] = static_cast<char>((stamp >> (8 * i)) & 0xffu);
}

void Session::reset(std::size_t channel_count) noexcept {
  channel_count_ = channel_count < kMaxChannels ? channel_count : kMaxChannels;
  subscriptions_.fill(kNone);
  status_head_ = status_count_ = 0;
  refused_ = replies_dropped_ = 0;
}

std::size_t Session::subscribed_channels() const noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < channel_count_; ++i) n += subscriptions_[i] != kNone;
  return n;
}

std::string_view Session::reply() const noexcept {
  return {statuses_[status_head_].data(), status_sizes_[status_head_]};
}

void Session::pop_reply() noexcept {
  if (status_count_ == 0) return;
  status_head_ = (status_head_ + 1) % kMaxStatuses;
  --status_count_;
}

void Session::status(StatusLevel level, const char* fmt, ...) noexcept {
  if (level == StatusLevel::error) ++refused_;
  if (status_count_ == kMaxStatuses) {
    ++replies_dropped_;  // the client sends faster than it reads its replies
    return;
  }
  char message[kStatusBytes - 64];
  std::va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(message, sizeof message, fmt, args);
  va_end(args);
  const std::size_t len = n < 0 ? 0 : (static_cast<std::size_t>(n) < sizeof message ? static_cast<std::size_t>(n) : sizeof message - 1);
  const std::size_t slot = (status_head_ + status_count_) % kMaxStatuses;
  // A message with bytes that are not UTF-8 (echoed from the client) is replaced.
  auto text = write_status(statuses_[slot], level, std::string_view(message, len));
  if (!text) text = write_status(statuses_[slot], level, "request refused");
  if (!text) return;
  status_sizes_[slot] = static_cast<std::uint16_t>(text->size());
  ++status_count_;
}

void Session::on_binary(std::span<const std::uint8_t> data) noexcept {
  status(StatusLevel::error, "read-only server: binary client messages (opcode %u, %zu bytes) are not accepted",
         data.empty() ? 0u : static_cast<unsigned>(data[0]), data.size());
}

void Session::on_text(std::string_view text) noexcept {
  if (Status s = document_.parse(text); !s) {
    status(StatusLevel::error, "malformed message: %s", s.error().c_str());
    return;
  }
  const json::Value root = document_.root();
  const json::Value op = root.find("op");
  if (!root.is(json::Type::object) || !op.is(json::Type::string)) {
    status(StatusLevel::error, "a client message is a JSON object with a string \"op\"");
    return;
  }
  if (op.string_equals("subscribe")) {
    subscribe(root.find("subscriptions"));
    return;
  }
  if (op.string_equals("unsubscribe")) {
    unsubscribe(root.find("subscriptionIds"));
    return;
  }
  char name[64];
  const std::string_view op_name = short_text(op, name);
  for (std::string_view read_only : kReadOnlyOps)
    if (op_name == read_only) {
      status(StatusLevel::error, "read-only server: \"%.*s\" is not supported", static_cast<int>(op_name.size()),
             op_name.data());
      return;
    }
  status(StatusLevel::error, "unknown op \"%.*s\"", static_cast<int>(op_name.size()), op_name.data());
}

void Session::subscribe(const json::Value& subscriptions) noexcept {
  if (!subscriptions.is(json::Type::array)) {
    status(StatusLevel::error, "subscribe: \"subscriptions\" must be an array");
    return;
  }
  for (json::Value item : subscriptions.items()) {
    const auto id = item.find("id").uint32();
    const auto channel = item.find("channelId").uint32();
    if (!item.is(json::Type::object) || !id || !channel) {
      status(StatusLevel::error, "subscribe: each subscription needs integer \"id\" and \"channelId\"");
      continue;
    }
    if (*channel >= channel_count_) {
      status(StatusLevel::warning, "subscribe: channel %u is not advertised", *channel);
      continue;
    }
    bool used = false;
    for (std::size_t c = 0; c < channel_count_; ++c) used = used || (subscriptions_[c] == *id && c != *channel);
    if (used || *id == kNone) {
      status(StatusLevel::error, "subscribe: subscription id %u is already in use", *id);
      continue;
    }
    if (subscriptions_[*channel] != kNone && subscriptions_[*channel] != *id) {
      status(StatusLevel::warning, "subscribe: channel %u is already subscribed as %u", *channel, subscriptions_[*channel]);
      continue;
    }
    subscriptions_[*channel] = *id;
  }
}

void Session::unsubscribe(const json::Value& ids) noexcept {
  if (!ids.is(json::Type::array)) {
    status(StatusLevel::error, "unsubscribe: \"subscriptionIds\" must be an array");
    return;
  }
  for (json::Value item : ids.items()) {
    const auto id = item.uint32();
    bool found = false;
    if (id)
      for (std::size_t c = 0; c < channel_count_; ++c)
        if (subscriptions_[c] == *id) {
          subscriptions_[c] = kNone;
          found = true;
        }
    if (!found) status(StatusLevel::warning, "unsubscribe: no subscription %u", id ? *id : kNone);
  }
}

}  // namespace sen3bot::view
