#pragma once
// The hand-off between the view task, which encodes each channel's newest message, and the
// server's thread, which sends them: per channel a triple buffer (the task writes one buffer,
// one holds the newest complete publish, the server sends from the third), so neither side
// ever waits for the other and a slow client only ever gets the newest message, never a queue
// of old ones. One publish may hold a few messages (the three transforms of /tf).
//
// Each message's payload is preceded by `headroom` bytes the server writes its frame header
// into, so a message goes out without a copy. All memory is taken once in create().
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <span>
#include <string_view>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/view/foxglove.hpp"

namespace sen3bot::view {

inline constexpr std::size_t kMaxChannels = 16;
inline constexpr std::size_t kMaxRecords = 4;  // messages per publish

struct ChannelSpec {
  std::string_view topic;  // static text
  Schema schema = Schema::grid;
  std::size_t capacity_bytes = 0;  // the payloads of one publish together
};

struct Record {
  std::size_t offset = 0;  // of the payload in the buffer
  std::size_t size = 0;
  hal::Nanos stamp_ns = 0;
};

// One publish: the messages of a channel at one moment. seq 0: nothing published yet.
struct Publication {
  std::uint64_t seq = 0;
  std::size_t record_count = 0;
  std::array<Record, kMaxRecords> records{};
  char* data = nullptr;  // the buffer; a payload is data + offset, its headroom just before

  [[nodiscard]] std::span<char> payload(std::size_t i) const noexcept { return {data + records[i].offset, records[i].size}; }
};

class ChannelBoard {
 public:
  // The buffers come from memory (a task's arena, or the heap's resource), once.
  static Result<std::unique_ptr<ChannelBoard>> create(std::span<const ChannelSpec> channels, std::size_t headroom,
                                                      std::pmr::memory_resource& memory);
  ~ChannelBoard();
  ChannelBoard(const ChannelBoard&) = delete;
  ChannelBoard& operator=(const ChannelBoard&) = delete;

  [[nodiscard]] std::size_t channel_count() const noexcept { return count_; }
  [[nodiscard]] const ChannelSpec& spec(std::size_t channel) const noexcept { return specs_[channel]; }
  [[nodiscard]] std::size_t headroom() const noexcept { return headroom_; }
  [[nodiscard]] std::size_t bytes() const noexcept { return bytes_; }  // all buffers together

  // --- producer (one thread) -------------------------------------------------------------
  // Room for the next message of the publish being built (empty when kMaxRecords are in).
  [[nodiscard]] std::span<char> space(std::size_t channel) noexcept;
  // The next message is the first `size` bytes of space().
  void commit(std::size_t channel, std::size_t size, hal::Nanos stamp_ns) noexcept;
  // Makes the messages committed since the last publish the channel's newest; a publish
  // without messages is ignored.
  void publish(std::size_t channel) noexcept;
  // Forgets the messages committed since the last publish.
  void discard(std::size_t channel) noexcept;
  [[nodiscard]] std::uint64_t published(std::size_t channel) const noexcept {
    return slots_[channel].published.load(std::memory_order_acquire);
  }

  // --- consumer (one thread) -------------------------------------------------------------
  // The channel's newest publish; what it points to stays valid until the next take() of the
  // same channel.
  const Publication& take(std::size_t channel) noexcept;

 private:
  ChannelBoard() = default;
  static constexpr std::uint8_t kFresh = 4;

  struct Slot {
    std::array<Publication, 3> buffers{};
    std::size_t capacity = 0;  // of each buffer
    std::uint8_t back = 0;     // the producer's
    std::uint8_t front = 1;    // the consumer's
    std::atomic<std::uint8_t> middle{2};  // the newest complete publish, | kFresh when unseen
    std::size_t used = 0;      // bytes of the back buffer taken by committed messages
    std::uint64_t next_seq = 1;
    std::atomic<std::uint64_t> published{0};
  };

  std::array<ChannelSpec, kMaxChannels> specs_{};
  std::array<Slot, kMaxChannels> slots_{};
  std::size_t count_ = 0;
  std::size_t headroom_ = 0;
  std::size_t bytes_ = 0;
  std::pmr::memory_resource* memory_ = nullptr;
  char* block_ = nullptr;
};

}  // namespace sen3bot::view
