#pragma once
// Errors at the edges are values. An Error carries a category and a short message in a
// fixed buffer, so building and returning one never allocates (real-time paths use them).
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>

namespace sen3bot {

enum class Errc : unsigned char {
  would_block,       // nothing available right now; try again later
  timeout,           // a deadline passed
  disconnected,      // the peer or device went away (EIO, ENODEV, HUP, EOF); reopen to recover
  io,                // any other operating-system I/O failure
  invalid_argument,  // the caller asked for something that cannot be valid
  not_supported,     // the platform lacks the feature (e.g. no AF_CAN in the kernel)
  permission,        // not permitted (e.g. SCHED_FIFO without CAP_SYS_NICE)
  protocol,          // bytes arrived that break the wire protocol
  capacity,          // a fixed-size buffer or budget is full
  not_found,         // a file, key or device does not exist
  config,            // a configuration value is missing or wrong
};

std::string_view to_string(Errc code) noexcept;

class Error {
 public:
  static constexpr std::size_t kMessageCapacity = 256;

  Error() = default;
  Error(Errc code, std::string_view message) noexcept : code_(code) { assign(message); }

  // printf-style construction; truncates rather than allocates.
  [[gnu::format(printf, 2, 3)]] static Error format(Errc code, const char* fmt, ...) noexcept {
    Error e;
    e.code_ = code;
    std::va_list args;
    va_start(args, fmt);
    const int n = std::vsnprintf(e.message_, kMessageCapacity, fmt, args);
    va_end(args);
    e.length_ = n < 0 ? 0 : (static_cast<std::size_t>(n) < kMessageCapacity ? static_cast<std::size_t>(n) : kMessageCapacity - 1);
    return e;
  }

  // An errno-based error: "<what>: <strerror(errnum)>".
  static Error from_errno(Errc code, std::string_view what, int errnum) noexcept;

  [[nodiscard]] Errc code() const noexcept { return code_; }
  [[nodiscard]] std::string_view message() const noexcept { return {message_, length_}; }
  [[nodiscard]] const char* c_str() const noexcept { return message_; }

 private:
  void assign(std::string_view text) noexcept {
    length_ = text.size() < kMessageCapacity ? text.size() : kMessageCapacity - 1;
    for (std::size_t i = 0; i < length_; ++i) message_[i] = text[i];
    message_[length_] = '\0';
  }

  Errc code_ = Errc::io;
  std::size_t length_ = 0;
  char message_[kMessageCapacity] = {};
};

// Result<T>: a value or an Error. Result<void> is spelled Status.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::in_place_index<0>, std::move(value)) {}  // NOLINT(implicit)
  Result(Error error) : state_(std::in_place_index<1>, error) {}          // NOLINT(implicit)

  [[nodiscard]] bool ok() const noexcept { return state_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  T& value() & { return std::get<0>(state_); }
  const T& value() const& { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  [[nodiscard]] const Error& error() const { return std::get<1>(state_); }

 private:
  std::variant<T, Error> state_;
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : failed_(true), error_(error) {}  // NOLINT(implicit)
  static Status success() { return {}; }

  [[nodiscard]] bool ok() const noexcept { return !failed_; }
  explicit operator bool() const noexcept { return ok(); }
  [[nodiscard]] const Error& error() const noexcept { return error_; }

 private:
  bool failed_ = false;
  Error error_;
};

}  // namespace sen3bot
