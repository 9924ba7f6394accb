#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::tasks {
namespace {

struct Pose {
  double x_m, y_m, yaw_rad;
  std::uint64_t tag;
};

TEST(Topic, NothingToReadBeforeTheFirstPublish) {
  Topic<Pose> topic;
  Sample<Pose> s;
  EXPECT_FALSE(topic.read(s));
  EXPECT_EQ(topic.published(), 0u);
}

TEST(Topic, ReadsTheLatestValueWithStampAndSequence) {
  Topic<Pose> topic;
  topic.publish({1, 2, 3, 7}, 100);
  topic.publish({4, 5, 6, 8}, 200);
  Sample<Pose> s;
  ASSERT_TRUE(topic.read(s));
  EXPECT_EQ(s.value.x_m, 4);
  EXPECT_EQ(s.value.tag, 8u);
  EXPECT_EQ(s.stamp_ns, 200);
  EXPECT_EQ(s.sequence, 2u);
  EXPECT_EQ(topic.published(), 2u);
}

TEST(Topic, ReadersNeverSeeATornValue) {
  struct Wide {
    std::uint64_t words[16];
  };
  Topic<Wide> topic;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    Wide w{};
    for (std::uint64_t n = 1; n <= 200'000; ++n) {
      for (auto& word : w.words) word = n;
      topic.publish(w, static_cast<hal::Nanos>(n));
    }
    done = true;
  });
  std::vector<std::thread> readers;
  std::atomic<std::uint64_t> torn{0}, reads{0};
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&] {
      Sample<Wide> s;
      std::uint64_t last = 0;
      while (!done) {
        if (!topic.read(s)) continue;
        ++reads;
        for (auto word : s.value.words)
          if (word != s.value.words[0]) ++torn;
        if (static_cast<std::uint64_t>(s.stamp_ns) != s.value.words[0]) ++torn;
        if (s.sequence < last) ++torn;  // time never goes backwards for one reader
        last = s.sequence;
      }
    });
  }
  writer.join();
  for (auto& t : readers) t.join();
  EXPECT_EQ(torn.load(), 0u);
  Sample<Wide> final_sample;
  ASSERT_TRUE(topic.read(final_sample));
  EXPECT_EQ(final_sample.value.words[15], 200'000u);
}

}  // namespace
}  // namespace sen3bot::tasks
