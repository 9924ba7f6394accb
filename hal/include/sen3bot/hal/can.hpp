#pragma once
// Classic CAN (ISO 11898-1, up to 8 data bytes): the frame type, acceptance filters, the
// CanBus interface, the Linux SocketCAN implementation (hal/posix) and an in-memory bus
// with several nodes for tests and simulation (hal/sim).
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "sen3bot/hal/fd.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

struct CanFrame {
  static constexpr std::uint32_t kMaxStandardId = 0x7FF;       // 11-bit identifier (base format)
  static constexpr std::uint32_t kMaxExtendedId = 0x1FFF'FFFF;  // 29-bit identifier (extended format)
  static constexpr std::size_t kMaxDataBytes = 8;              // classic CAN, not CAN FD

  std::uint32_t id = 0;
  bool extended = false;  // 29-bit identifier
  bool rtr = false;       // remote request: dlc is the requested length, data is not sent
  std::uint8_t dlc = 0;   // 0..8
  std::array<std::uint8_t, kMaxDataBytes> data{};

  // A well-formed data frame; Errc::invalid_argument if the payload or id does not fit.
  static Result<CanFrame> make(std::uint32_t id, std::span<const std::uint8_t> payload, bool extended = false);

  // Errc::invalid_argument when dlc > 8 or the id has bits beyond 11 (or 29) bits.
  [[nodiscard]] Status validate() const;
  [[nodiscard]] std::span<const std::uint8_t> payload() const noexcept {
    return {data.data(), dlc <= kMaxDataBytes ? dlc : kMaxDataBytes};
  }

  friend bool operator==(const CanFrame&, const CanFrame&) = default;
};
static_assert(std::is_trivially_copyable_v<CanFrame>, "frames cross thread boundaries by copy");

// Acceptance filter with Linux can_filter semantics: a frame passes when
// (frame.id & mask) == (id & mask), and, unless format is any, its id format matches.
struct CanFilter {
  enum class Format : std::uint8_t { any, standard, extended };

  std::uint32_t id = 0;
  std::uint32_t mask = 0;  // identifier bits that must match; 0 accepts every id
  Format format = Format::any;

  [[nodiscard]] bool matches(const CanFrame& frame) const noexcept {
    if (format == Format::standard && frame.extended) return false;
    if (format == Format::extended && !frame.extended) return false;
    return ((frame.id ^ id) & mask) == 0;
  }
};

// The controller's fault confinement state (ISO 11898-1): error active is normal; warning and
// passive mean many errors; bus-off means the controller has left the bus and sends nothing.
enum class CanLinkState : std::uint8_t { active, warning, passive, bus_off };
[[nodiscard]] const char* to_string(CanLinkState state) noexcept;

// The most filters one bus handle keeps (a fixed array, so set_filters never allocates).
constexpr std::size_t kMaxCanFilters = 16;

class CanBus {
 public:
  virtual ~CanBus() = default;

  // Queues one frame. Errc::invalid_argument for a malformed frame, Errc::would_block when
  // the transmit queue is full (retry later), Errc::disconnected when the bus is down.
  virtual Status send(const CanFrame& frame) = 0;
  // One frame that passed the filters, or std::nullopt when none is waiting.
  virtual Result<std::optional<CanFrame>> receive() = 0;
  // Replaces the acceptance filters; a frame is received when any filter matches. As with
  // SocketCAN, an empty set receives nothing, and a new handle starts accepting everything.
  virtual Status set_filters(std::span<const CanFilter> filters) = 0;
  Status accept_all() {
    const CanFilter everything{};
    return set_filters({&everything, 1});
  }

  // The link's state as last reported (SocketCAN: by the kernel's error frames, read by
  // receive()). A user that needs the bus (the e-stop chain) treats bus_off as lost.
  [[nodiscard]] virtual CanLinkState link_state() const { return CanLinkState::active; }

  // A descriptor to poll for readability, or -1 (the in-memory bus: poll by receiving).
  [[nodiscard]] virtual int poll_fd() const { return -1; }
  [[nodiscard]] virtual std::string_view name() const = 0;
};

struct SocketCanOptions {
  bool receive_own = false;  // CAN_RAW_RECV_OWN_MSGS: also receive what this socket sent
};

// socket(PF_CAN, SOCK_RAW, CAN_RAW) bound to one interface, non-blocking. On a kernel
// without AF_CAN, open() fails with Errc::not_supported and says so.
class SocketCanBus final : public CanBus {
 public:
  static Result<std::unique_ptr<SocketCanBus>> open(std::string_view interface, SocketCanOptions options = {});
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  Status send(const CanFrame& frame) override;
  Result<std::optional<CanFrame>> receive() override;
  Status set_filters(std::span<const CanFilter> filters) override;
  [[nodiscard]] int poll_fd() const override { return fd_.get(); }
  [[nodiscard]] std::string_view name() const override { return name_; }

 private:
  SocketCanBus(UniqueFd fd, std::string name);

  UniqueFd fd_;
  std::string name_;
};

class MemoryCanBus;

struct MemoryCanNodeOptions {
  std::size_t receive_queue_frames = 64;  // fixed at attach(); overflow drops the new frame
  bool receive_own = false;               // like CAN_RAW_RECV_OWN_MSGS
};

// One station on a MemoryCanBus. Thread-safe: each node may live on its own thread (the
// bus takes a short mutex; no allocation after attach()).
class MemoryCanNode final : public CanBus {
 public:
  MemoryCanNode(const MemoryCanNode&) = delete;
  MemoryCanNode& operator=(const MemoryCanNode&) = delete;

  // Delivers to every other attached node whose filters accept the frame (and to this node
  // if receive_own). A full receive queue drops the frame for that node only and counts it.
  Status send(const CanFrame& frame) override;
  // Queued frames are still returned after the bus went down; then Errc::disconnected.
  Result<std::optional<CanFrame>> receive() override;
  Status set_filters(std::span<const CanFilter> filters) override;
  [[nodiscard]] std::string_view name() const override { return name_; }
  [[nodiscard]] CanLinkState link_state() const override;

  [[nodiscard]] std::size_t queued_frames() const;
  [[nodiscard]] std::uint64_t overflow_count() const;  // frames dropped on a full queue
  [[nodiscard]] std::uint64_t sent_count() const;
  [[nodiscard]] std::uint64_t received_count() const;  // frames taken by receive()

 private:
  friend class MemoryCanBus;
  MemoryCanNode(MemoryCanBus& bus, std::string name, MemoryCanNodeOptions options);
  bool accepts(const CanFrame& frame) const noexcept;  // bus mutex held
  void deliver(const CanFrame& frame) noexcept;        // bus mutex held

  MemoryCanBus& bus_;
  std::string name_;
  MemoryCanNodeOptions options_;
  std::unique_ptr<CanFrame[]> queue_;
  std::size_t queue_head_ = 0;  // oldest frame
  std::size_t queue_count_ = 0;
  std::array<CanFilter, kMaxCanFilters> filters_{};
  std::size_t filter_count_ = 1;  // filters_[0] = {} accepts everything
  std::uint64_t overflow_count_ = 0;
  std::uint64_t sent_count_ = 0;
  std::uint64_t received_count_ = 0;
};

// A simulated bus: every frame sent by one node reaches all the others, as on a real
// bus. Nodes are owned by the bus and live as long as it does.
class MemoryCanBus {
 public:
  explicit MemoryCanBus(std::size_t max_nodes = 8);
  MemoryCanBus(const MemoryCanBus&) = delete;
  MemoryCanBus& operator=(const MemoryCanBus&) = delete;

  // Allocates the node and its queue here, never later. Errc::capacity past max_nodes,
  // Errc::invalid_argument for a zero-length queue.
  Result<MemoryCanNode*> attach(std::string_view name, MemoryCanNodeOptions options = {});

  // A bus that is down (cable cut, bus-off) makes send() and, once drained, receive()
  // report Errc::disconnected on every node until it is brought up again.
  void set_link_up(bool up);
  [[nodiscard]] bool link_up() const;
  // What every node's link_state() reports; bus_off takes the link down as set_link_up(false)
  // does, any other state brings it up.
  void set_link_state(CanLinkState state);
  [[nodiscard]] CanLinkState link_state() const;
  [[nodiscard]] std::uint64_t frames_sent() const;  // frames put on the bus, all nodes

 private:
  friend class MemoryCanNode;

  mutable std::mutex mutex_;
  std::size_t max_nodes_;
  std::vector<std::unique_ptr<MemoryCanNode>> nodes_;
  bool link_up_ = true;
  CanLinkState link_state_ = CanLinkState::active;
  std::uint64_t frames_sent_ = 0;
};

}  // namespace sen3bot::hal
