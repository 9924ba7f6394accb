#pragma once
// Classic CAN (ISO 11898-1, up to 8 data bytes): the frame type, acceptance filters, the
// CanBus interface, the Linux SocketCAN implementation (hal/posix) and an in-memory bus
// with several nodes for tests and simulation (hal/sim).
#include <array>
#include <atomic>
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

// The state after one of the kernel's error frames, its id holding the error classes
// (hal::can_error in candump.hpp; parse_candump_line gives the same frame: extended, dlc 8).
// Bus-off wins over anything else in the frame. Restarted means back on the bus: active,
// unless the frame also reports the controller's state (data[1]), which then decides:
// passive bits over warning bits over kActive. A controller report clears bus-off too (the
// controller is talking again, e.g. after the hardware's own recovery). Other classes (bus
// errors, lost arbitration, no ACK, a transmit timeout) and the overflow bits leave the state
// as it was. Pure: no OS dependency, so it is tested without a kernel.
[[nodiscard]] CanLinkState next_link_state(CanLinkState current, const CanFrame& error_frame) noexcept;

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

  // The kernel's receive time (Unix ns) of the frame last returned by receive(), or -1 when
  // the backend has none (the in-memory bus) or the kernel gave none. Unlike the time the
  // frame was read, it does not include the wait for the reading task's next cycle.
  [[nodiscard]] virtual std::int64_t last_receive_unix_ns() const { return -1; }

  // Retries the frames waiting in the backend's transmit queue, oldest first. Success when
  // none is left; Errc::would_block when the controller still has no room (they stay
  // queued); Errc::disconnected when the bus is down. Call it every cycle: queued frames
  // otherwise wait for the next send(), which flushes first. The default has no queue.
  virtual Status flush() { return {}; }
  // Frames waiting in the transmit queue, and frames dropped because it was full or the
  // bus went off (the default: no queue, nothing dropped).
  [[nodiscard]] virtual std::size_t tx_queued() const { return 0; }
  [[nodiscard]] virtual std::uint64_t tx_dropped() const { return 0; }
  // Error frames read from the kernel (bus-off, controller state, restarted, tx timeout).
  [[nodiscard]] virtual std::uint64_t error_frames() const { return 0; }

  // A descriptor to poll for readability, or -1 (the in-memory bus: poll by receiving).
  [[nodiscard]] virtual int poll_fd() const { return -1; }
  [[nodiscard]] virtual std::string_view name() const = 0;
};

// A fixed ring of frames waiting for room in the controller's transmit queue, oldest first.
// The kernel refuses a frame (ENOBUFS) while the bus is busy or nobody ACKs; rather than the
// caller losing it, or resending frames out of order, it waits here. Storage is allocated by
// the constructor only (at SocketCanBus::open()); nothing after. Not thread-safe: it belongs
// to the sending thread. Pure logic: the write is a callback, so it is tested without a kernel.
class CanTxRing {
 public:
  // Hands one frame to the controller: success, or Errc::would_block when it has no room now
  // (the frame is queued). Any other error is passed to the caller: a waiting frame stays
  // queued, a new one is not taken.
  using WriteFn = Status (*)(void* context, const CanFrame& frame);

  // capacity 0: no queue, a refused frame is dropped at once. `name` (the interface, cut to
  // 31 characters) starts the error messages.
  CanTxRing(std::size_t capacity, std::string_view name);
  CanTxRing(const CanTxRing&) = delete;
  CanTxRing& operator=(const CanTxRing&) = delete;

  // Flushes, then writes the frame, or appends it behind the waiting ones so the order on the
  // bus is the order of the calls. Success when written or queued; Errc::would_block when the
  // ring is full (the frame is dropped and counted); a flush error other than would_block is
  // returned and the frame is not taken.
  Status send(const CanFrame& frame, WriteFn write, void* context);
  // Writes the waiting frames, oldest first, until one is refused: see CanBus::flush().
  Status flush(WriteFn write, void* context);
  // Callable forms: write(const CanFrame&) -> Status.
  template <class Write>
  Status send(const CanFrame& frame, Write& write) {
    return send(frame, &call<Write>, &write);
  }
  template <class Write>
  Status flush(Write& write) {
    return flush(&call<Write>, &write);
  }

  // Appends behind the others; false when full (the frame is dropped and counted).
  bool push(const CanFrame& frame) noexcept;
  // Drops every waiting frame (counted): after a bus-off they would be stale. How many.
  std::size_t discard() noexcept;

  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  [[nodiscard]] bool empty() const noexcept { return count_ == 0; }
  [[nodiscard]] const CanFrame& front() const noexcept { return frames_[head_]; }  // !empty()
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }

 private:
  template <class Write>
  static Status call(void* context, const CanFrame& frame) {
    return (*static_cast<Write*>(context))(frame);
  }
  void pop() noexcept;

  std::unique_ptr<CanFrame[]> frames_;
  std::size_t capacity_;
  std::size_t head_ = 0;  // oldest frame
  std::size_t count_ = 0;
  std::uint64_t dropped_ = 0;
  std::array<char, 32> name_{};
};

// A handle on a bus someone else owns (a station of a MemoryCanBus, kept by its bus), for an
// interface that hands out owned CanBus objects (hal::Board::open_can).
class CanBusRef final : public CanBus {
 public:
  explicit CanBusRef(CanBus& bus) noexcept : bus_(bus) {}
  Status send(const CanFrame& frame) override { return bus_.send(frame); }
  Result<std::optional<CanFrame>> receive() override { return bus_.receive(); }
  Status set_filters(std::span<const CanFilter> filters) override { return bus_.set_filters(filters); }
  [[nodiscard]] CanLinkState link_state() const override { return bus_.link_state(); }
  [[nodiscard]] std::int64_t last_receive_unix_ns() const override { return bus_.last_receive_unix_ns(); }
  Status flush() override { return bus_.flush(); }
  [[nodiscard]] std::size_t tx_queued() const override { return bus_.tx_queued(); }
  [[nodiscard]] std::uint64_t tx_dropped() const override { return bus_.tx_dropped(); }
  [[nodiscard]] std::uint64_t error_frames() const override { return bus_.error_frames(); }
  [[nodiscard]] int poll_fd() const override { return bus_.poll_fd(); }
  [[nodiscard]] std::string_view name() const override { return bus_.name(); }

 private:
  CanBus& bus_;
};

struct SocketCanOptions {
  bool receive_own = false;  // CAN_RAW_RECV_OWN_MSGS: also receive what this socket sent
  // Frames kept when the kernel's transmit queue is full (CanTxRing), allocated at open();
  // 0: no queue, such a frame is refused with Errc::would_block.
  std::size_t tx_queue_frames = 16;
};

// socket(PF_CAN, SOCK_RAW, CAN_RAW) bound to one interface, non-blocking. On a kernel
// without AF_CAN, open() fails with Errc::not_supported and says so.
//
// The socket asks for the kernel's error frames (bus-off, controller state, restarted, tx
// timeout): receive() counts them and follows the link state with next_link_state(), never
// returning them as data. While bus-off, send() and flush() refuse with Errc::disconnected
// and the queued frames are dropped, until a restarted or controller frame says the
// controller is back. Frames carry the kernel's receive time (SO_TIMESTAMPNS).
//
// One thread may send (send, flush, tx_queued, tx_dropped) while another receives (receive,
// last_receive_unix_ns): they share only the atomic link state and error count.
class SocketCanBus final : public CanBus {
 public:
  static Result<std::unique_ptr<SocketCanBus>> open(std::string_view interface, SocketCanOptions options = {});
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  // Success when the frame was handed to the kernel or queued behind earlier ones.
  Status send(const CanFrame& frame) override;
  Result<std::optional<CanFrame>> receive() override;
  Status set_filters(std::span<const CanFilter> filters) override;
  [[nodiscard]] int poll_fd() const override { return fd_.get(); }
  [[nodiscard]] std::string_view name() const override { return name_; }
  [[nodiscard]] CanLinkState link_state() const override { return link_state_.load(std::memory_order_acquire); }
  [[nodiscard]] std::int64_t last_receive_unix_ns() const override { return last_receive_unix_ns_; }

  Status flush() override;
  [[nodiscard]] std::size_t tx_queued() const override { return tx_.size(); }
  [[nodiscard]] std::uint64_t tx_dropped() const override { return tx_.dropped(); }
  [[nodiscard]] std::uint64_t error_frames() const override {
    return error_frames_.load(std::memory_order_relaxed);
  }

 private:
  SocketCanBus(UniqueFd fd, std::string name, std::size_t tx_queue_frames);
  Status write_frame(const CanFrame& frame);  // one write(); would_block when the kernel is full
  static Status write_to(void* self, const CanFrame& frame);
  Status refuse_if_bus_off();

  UniqueFd fd_;
  std::string name_;
  CanTxRing tx_;
  std::atomic<CanLinkState> link_state_{CanLinkState::active};
  std::atomic<std::uint64_t> error_frames_{0};
  std::int64_t last_receive_unix_ns_ = -1;
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
