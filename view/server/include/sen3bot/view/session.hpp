#pragma once
// The foxglove.websocket.v1 subprotocol as this read-only server speaks it, without any I/O:
// the server's own text messages (serverInfo, advertise, status) and one client's operations.
// A client may subscribe and unsubscribe; every other operation, binary client messages, text
// that is not a JSON object and unknown operations get a status error and change nothing.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/view/channel_board.hpp"
#include "sen3bot/view/foxglove.hpp"

namespace sen3bot::view {

inline constexpr std::string_view kSubprotocol = "foxglove.websocket.v1";
inline constexpr std::uint8_t kOpMessageData = 0x01;
inline constexpr std::size_t kFrameHeader = 1 + 4 + 8;  // opcode, subscription id, timestamp

enum class StatusLevel : std::uint8_t { info = 0, warning = 1, error = 2 };

// {"op":"serverInfo",...}: no capabilities, since no channel takes anything from a client.
Result<std::string_view> write_server_info(std::span<char> out, std::string_view name, std::string_view session_id) noexcept;
// {"op":"advertise","channels":[...]} with channel ids 0..n-1 as the board's channels.
Result<std::string_view> write_advertise(std::span<char> out, const ChannelBoard& board) noexcept;
Result<std::string_view> write_status(std::span<char> out, StatusLevel level, std::string_view message) noexcept;
// The 13-byte header of a message data frame.
void write_frame_header(std::span<char, kFrameHeader> out, std::uint32_t subscription_id, hal::Nanos stamp_ns) noexcept;

class Session {
 public:
  static constexpr std::size_t kStatusBytes = 512;
  static constexpr std::size_t kMaxStatuses = 8;  // a reply per operation; more are dropped
  static constexpr std::uint32_t kNone = 0xffffffffu;
  static constexpr std::size_t kMaxTokens = 512;  // a subscribe of every channel needs ~100
  static constexpr std::size_t kMaxTextBytes = 64 * 1024;  // the server closes on longer ones

  explicit Session(std::size_t channel_count = 0) noexcept { reset(channel_count); }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  void reset(std::size_t channel_count) noexcept;

  // One whole client text message. Replies (status messages) queue up for the server to send.
  void on_text(std::string_view text) noexcept;
  // A binary client message: this server takes none.
  void on_binary(std::span<const std::uint8_t> data) noexcept;

  // The client's subscription id for a channel, or kNone.
  [[nodiscard]] std::uint32_t subscription(std::size_t channel) const noexcept { return subscriptions_[channel]; }
  [[nodiscard]] std::size_t subscribed_channels() const noexcept;

  // Replies waiting, oldest first.
  [[nodiscard]] bool has_reply() const noexcept { return status_count_ > 0; }
  [[nodiscard]] std::string_view reply() const noexcept;
  void pop_reply() noexcept;
  // How many client messages were refused (an error status), and replies dropped unsent.
  [[nodiscard]] std::uint64_t refused() const noexcept { return refused_; }
  [[nodiscard]] std::uint64_t replies_dropped() const noexcept { return replies_dropped_; }

 private:
  [[gnu::format(printf, 3, 4)]] void status(StatusLevel level, const char* fmt, ...) noexcept;
  void subscribe(const json::Value& subscriptions) noexcept;
  void unsubscribe(const json::Value& ids) noexcept;

  std::size_t channel_count_ = 0;
  std::array<std::uint32_t, kMaxChannels> subscriptions_{};
  std::array<std::array<char, kStatusBytes>, kMaxStatuses> statuses_{};
  std::array<std::uint16_t, kMaxStatuses> status_sizes_{};
  std::size_t status_head_ = 0;
  std::size_t status_count_ = 0;
  std::uint64_t refused_ = 0;
  std::uint64_t replies_dropped_ = 0;
  json::StaticDocument<kMaxTokens> document_{json::Limits{8, kMaxTextBytes}};
};

}  // namespace sen3bot::view
