#include <gtest/gtest.h>

#include <cstring>
#include <thread>
#include <vector>

#include "sen3bot/tasks/event_log.hpp"

namespace sen3bot::tasks {
namespace {

TEST(EventLog, PostsAndPopsInOrder) {
  EventLog<8> log;
  EXPECT_TRUE(log.post(10, Severity::info, "p2os", "connected at %d baud", 9600));
  EXPECT_TRUE(log.post(20, Severity::error, "lms200", "no scan for %d ms", 80));
  Event e;
  ASSERT_TRUE(log.pop(e));
  EXPECT_STREQ(e.source, "p2os");
  EXPECT_STREQ(e.text, "connected at 9600 baud");
  EXPECT_EQ(e.stamp_ns, 10);
  ASSERT_TRUE(log.pop(e));
  EXPECT_EQ(e.severity, Severity::error);
  EXPECT_FALSE(log.pop(e));
}

TEST(EventLog, DropsAndCountsWhenFullAndTruncatesLongText) {
  EventLog<4> log;
  for (int i = 0; i < 6; ++i) log.post(i, Severity::info, "a-very-long-source-name", "%0200d", i);
  EXPECT_EQ(log.dropped(), 2u);
  Event e;
  int popped = 0;
  while (log.pop(e)) {
    EXPECT_EQ(std::strlen(e.text), Event::kTextCapacity - 1);
    EXPECT_EQ(std::strlen(e.source), sizeof e.source - 1);
    ++popped;
  }
  EXPECT_EQ(popped, 4);
  EXPECT_TRUE(log.post(9, Severity::info, "x", "room again"));
}

TEST(EventLog, ManyProducersOneConsumerLoseNothingUncounted) {
  EventLog<64> log;
  constexpr int kProducers = 4;
  constexpr int kPerProducer = 20'000;
  std::atomic<int> finished{0};
  std::vector<std::thread> producers;
  for (int p = 0; p < kProducers; ++p) {
    producers.emplace_back([&, p] {
      for (int i = 0; i < kPerProducer; ++i) log.post(i, Severity::info, "t", "%d %d", p, i);
      ++finished;
    });
  }
  std::vector<int> next(kProducers, 0);
  std::uint64_t received = 0;
  bool ordered = true;
  Event e;
  auto take = [&](const Event& ev) {
    int p = -1, i = -1;
    if (std::sscanf(ev.text, "%d %d", &p, &i) != 2 || p < 0 || p >= kProducers) {
      ordered = false;
      return;
    }
    if (i < next[static_cast<std::size_t>(p)]) ordered = false;  // per-producer FIFO
    next[static_cast<std::size_t>(p)] = i + 1;
    ++received;
  };
  for (;;) {
    const bool all_posted = finished.load() == kProducers;
    bool any = false;
    while (log.pop(e)) {
      take(e);
      any = true;
    }
    if (all_posted && !any) break;
  }
  for (auto& t : producers) t.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(received + log.dropped(), static_cast<std::uint64_t>(kProducers) * kPerProducer);
}

}  // namespace
}  // namespace sen3bot::tasks
