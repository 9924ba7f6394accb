#pragma once
// A board for tests of the device tasks: each named link is the near end of an in-memory pipe
// the test owns (the far end talks to an emulator), with an optional rate control, on a
// simulated clock. Counts the opens, so reconnects can be checked.
#include <map>
#include <memory>
#include <string>

#include "sen3bot/hal/board.hpp"
#include "sen3bot/hal/memory_stream.hpp"

namespace sen3bot::testing {

class PipeBoard final : public hal::Board {
 public:
  explicit PipeBoard(hal::Nanos start_ns = 0) : clock_(start_ns) {}

  void attach(const std::string& link, hal::ByteStream& stream, hal::BaudControl* baud = nullptr) {
    links_[link] = Entry{&stream, baud};
  }
  [[nodiscard]] int opens(const std::string& link) const {
    auto it = opens_.find(link);
    return it == opens_.end() ? 0 : it->second;
  }
  // Open calls, including those that found no link.
  [[nodiscard]] int attempts(const std::string& link) const {
    auto it = attempts_.find(link);
    return it == attempts_.end() ? 0 : it->second;
  }

  [[nodiscard]] std::string_view name() const override { return "pipe"; }
  [[nodiscard]] hal::Clock& clock() override { return clock_; }
  [[nodiscard]] hal::SimClock* lockstep_clock() noexcept override { return &clock_; }
  [[nodiscard]] hal::SimClock& sim_clock() noexcept { return clock_; }
  Result<hal::Link> open_link(std::string_view link, const hal::LinkRequest& request) override {
    ++attempts_[std::string(link)];
    auto it = links_.find(std::string(link));
    if (it == links_.end()) return Error(Errc::not_found, "pipe board: no such link");
    ++opens_[std::string(link)];
    hal::Link opened;
    opened.stream = std::make_unique<Borrowed>(*it->second.stream);
    opened.baud_control = it->second.baud;
    opened.baud = request.baud;
    return opened;
  }

 private:
  struct Entry {
    hal::ByteStream* stream = nullptr;
    hal::BaudControl* baud = nullptr;
  };
  class Borrowed final : public hal::ByteStream {
   public:
    explicit Borrowed(hal::ByteStream& inner) : inner_(inner) {}
    Result<std::size_t> read(std::span<std::uint8_t> out) override { return inner_.read(out); }
    Result<std::size_t> write(std::span<const std::uint8_t> data) override { return inner_.write(data); }
    [[nodiscard]] std::string_view name() const override { return inner_.name(); }

   private:
    hal::ByteStream& inner_;
  };

  hal::SimClock clock_;
  std::map<std::string, Entry> links_;
  std::map<std::string, int> opens_;
  std::map<std::string, int> attempts_;
};

}  // namespace sen3bot::testing
