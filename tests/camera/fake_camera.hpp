#pragma once
// A fake RTSP camera of ours on 127.0.0.1 that replays recorded replies of real cameras
// (tests/data/camera/rtsp/), for tests that need a server which answers like one.
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::camera::testing {

// Puts the request's CSeq into a recorded reply and makes Content-Length match the body.
inline std::string adapt_reply(const std::string& recorded, std::uint32_t cseq) {
  const std::size_t split = recorded.find("\r\n\r\n");
  const std::string head = recorded.substr(0, split);
  const std::string body = split == std::string::npos ? "" : recorded.substr(split + 4);
  std::string out;
  std::size_t pos = 0;
  while (pos < head.size()) {
    std::size_t eol = head.find("\r\n", pos);
    if (eol == std::string::npos) eol = head.size();
    const std::string line = head.substr(pos, eol - pos);
    pos = eol + 2;
    const std::string lower = [&] {
      std::string l = line.substr(0, line.find(':'));
      for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return l;
    }();
    if (lower == "cseq" || lower == "content-length") continue;
    out += line + "\r\n";
  }
  out += "CSeq: " + std::to_string(cseq) + "\r\n";
  if (!body.empty()) out += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  return out + "\r\n" + body;
}

// Answers each request with the recorded reply for its method (200 with Public: for the rest);
// an empty reply closes the connection instead.
class FakeCamera {
 public:
  explicit FakeCamera(std::map<std::string, std::string> replies) : replies_(std::move(replies)) {
    auto listener = hal::TcpListener::listen("127.0.0.1", 0);
    EXPECT_TRUE(listener.ok());
    listener_ = std::move(*listener);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeCamera() {
    stop_ = true;
    thread_.join();
  }
  std::uint16_t port() const { return listener_->port(); }
  std::vector<std::string> requests() {
    std::lock_guard lock(mutex_);
    return requests_;
  }
  int accepted() const { return accepted_.load(); }
  int count(const std::string& method) {
    std::lock_guard lock(mutex_);
    return static_cast<int>(std::count_if(requests_.begin(), requests_.end(),
                                          [&](const std::string& r) { return r.starts_with(method + " "); }));
  }
  int authorized() const { return authorized_.load(); }
  // The n-th request of `method` gets replies[n] (the last one from then on); before any client
  // connects.
  void set_sequence(const std::string& method, std::vector<std::string> replies) {
    std::lock_guard lock(mutex_);
    sequences_[method] = std::move(replies);
  }

 private:
  void run() {
    struct Client {
      std::unique_ptr<hal::TcpStream> stream;
      std::string buf;
    };
    std::vector<Client> clients;
    while (!stop_) {
      if (auto s = listener_->accept(); s && *s) {
        ++accepted_;
        clients.push_back(Client{std::move(*s), {}});
      }
      for (Client& c : clients) {
        if (!c.stream) continue;
        std::uint8_t tmp[4096];
        auto n = c.stream->read(tmp);
        if (!n) {
          c.stream.reset();
          continue;
        }
        if (*n == 0) continue;
        c.buf.append(reinterpret_cast<const char*>(tmp), *n);
        std::size_t consumed = 0;
        while (c.stream) {
          auto msg = parse_message(c.buf, &consumed);
          if (!msg) break;
          const std::string method(msg->method);
          std::string recorded;
          bool have_recorded = false;
          {
            std::lock_guard lock(mutex_);
            requests_.push_back(method + " " + std::string(msg->uri));
            if (auto it = sequences_.find(method); it != sequences_.end() && !it->second.empty()) {
              const auto nth = static_cast<std::size_t>(
                  std::count_if(requests_.begin(), requests_.end(), [&](const std::string& r) { return r.starts_with(method + " "); }));
              recorded = it->second[std::min(nth, it->second.size()) - 1];
              have_recorded = true;
            } else if (auto found = replies_.find(method); found != replies_.end()) {
              recorded = found->second;
              have_recorded = true;
            }
          }
          if (msg->header("Authorization")) ++authorized_;
          std::string reply;
          if (have_recorded) {
            if (recorded.empty()) {
              c.stream.reset();
              break;
            }
            reply = adapt_reply(recorded, msg->cseq().value_or(0));
          } else {
            reply = "RTSP/1.0 200 OK\r\nCSeq: " + std::to_string(msg->cseq().value_or(0)) +
                    "\r\nPublic: OPTIONS, DESCRIBE, SETUP, PLAY, TEARDOWN\r\n\r\n";
          }
          (void)c.stream->write(std::span(reinterpret_cast<const std::uint8_t*>(reply.data()), reply.size()));
          c.buf.erase(0, consumed);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  std::map<std::string, std::string> replies_;
  std::map<std::string, std::vector<std::string>> sequences_;
  std::unique_ptr<hal::TcpListener> listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> accepted_{0};
  std::atomic<int> authorized_{0};
  std::mutex mutex_;
  std::vector<std::string> requests_;
};

}  // namespace sen3bot::camera::testing
