#include "sen3bot/mem/bounded_index_heap.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <utility>
#include <vector>

#include "sen3bot/mem/budget_arena.hpp"

namespace sen3bot::mem {
namespace {

using Heap = BoundedIndexHeap<float>;
using Key = Heap::Key;

// Owns caller-side storage for a heap, as a planner would keep it in its own arena.
struct HeapWithStorage {
  explicit HeapWithStorage(std::size_t capacity) : nodes(capacity), positions(capacity) {
    EXPECT_TRUE(heap.init(nodes, positions).ok());
  }
  std::vector<Heap::Node> nodes;
  std::vector<Key> positions;
  Heap heap;
};

std::vector<std::pair<float, Key>> drain(Heap& heap) {
  std::vector<std::pair<float, Key>> out;
  while (auto node = heap.pop()) out.emplace_back(node->priority, node->key);
  return out;
}

TEST(BoundedIndexHeapTest, UninitialisedHeapHasNoRoom) {
  Heap heap;
  EXPECT_EQ(heap.capacity(), 0u);
  EXPECT_TRUE(heap.empty());
  EXPECT_FALSE(heap.push(0, 1.0F));
  EXPECT_FALSE(heap.contains(0));
  EXPECT_EQ(heap.pop(), std::nullopt);
}

TEST(BoundedIndexHeapTest, InitFromCallerSpans) {
  std::array<Heap::Node, 8> nodes{};
  std::array<Key, 5> positions{};
  Heap heap;
  ASSERT_TRUE(heap.init(nodes, positions).ok());
  EXPECT_EQ(heap.capacity(), 5u);
  EXPECT_TRUE(heap.push(4, 1.0F));
  EXPECT_FALSE(heap.push(5, 1.0F)) << "key out of range";

  std::array<Heap::Node, 2> too_few{};
  const Status status = heap.init(too_few, positions);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code(), Errc::invalid_argument);
  EXPECT_EQ(status.error().message(), "index heap: 2 node slots for a capacity of 5 keys");
  EXPECT_EQ(heap.capacity(), 0u);
}

TEST(BoundedIndexHeapTest, InitFromAnArenaUsesExactlyStorageBytes) {
  BudgetArena arena("planner", 64 * 1024);
  Heap heap;
  ASSERT_TRUE(heap.init(1000, &arena).ok());
  EXPECT_EQ(heap.capacity(), 1000u);
  EXPECT_EQ(Heap::storage_bytes(1000), 1000u * 12u) << "float priority: 12 B per key";
  EXPECT_EQ(arena.used_bytes(), Heap::storage_bytes(1000));
  EXPECT_TRUE(heap.push(999, 0.5F));
}

TEST(BoundedIndexHeapTest, InitOverBudgetReportsTheArenaError) {
  BudgetArena arena("planner", 1024);
  Heap heap;
  const Status status = heap.init(1000, &arena);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code(), Errc::capacity);
  EXPECT_EQ(status.error().message(),
            "arena 'planner': budget 1024 B exceeded: request of 8000 B (align 4) with 0 B in use");
  EXPECT_EQ(heap.capacity(), 0u);
}

TEST(BoundedIndexHeapTest, InitFromAPlainResourceThatFails) {
  Heap heap;
  const Status status = heap.init(10, std::pmr::null_memory_resource());
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().message(), "index heap: cannot allocate 120 B for 10 keys");
}

TEST(BoundedIndexHeapTest, PushPopInPriorityOrder) {
  HeapWithStorage h(10);
  Heap& heap = h.heap;
  EXPECT_TRUE(heap.push(3, 3.0F));
  EXPECT_TRUE(heap.push(1, 1.0F));
  EXPECT_TRUE(heap.push(7, 0.5F));
  EXPECT_TRUE(heap.push(2, 2.0F));
  EXPECT_FALSE(heap.push(3, 0.1F)) << "already queued";
  EXPECT_EQ(heap.size(), 4u);
  EXPECT_EQ(heap.top().key, 7u);
  EXPECT_EQ(heap.priority(2), 2.0F);
  EXPECT_EQ(drain(heap), (std::vector<std::pair<float, Key>>{{0.5F, 7}, {1.0F, 1}, {2.0F, 2}, {3.0F, 3}}));
  EXPECT_FALSE(heap.contains(7));
  EXPECT_TRUE(heap.push(7, 9.0F)) << "a popped key can be queued again";
}

TEST(BoundedIndexHeapTest, EqualPrioritiesPopLowerKeyFirstWhateverThePushOrder) {
  const std::vector<Key> orders[] = {{5, 3, 9, 1, 0}, {0, 1, 3, 5, 9}, {9, 5, 3, 1, 0}, {3, 0, 9, 1, 5}};
  for (const auto& order : orders) {
    HeapWithStorage h(10);
    for (Key key : order) ASSERT_TRUE(h.heap.push(key, 2.0F));
    ASSERT_TRUE(h.heap.push(4, 1.0F));
    std::vector<Key> popped;
    while (auto node = h.heap.pop()) popped.push_back(node->key);
    EXPECT_EQ(popped, (std::vector<Key>{4, 0, 1, 3, 5, 9}));
  }
}

TEST(BoundedIndexHeapTest, TieBreakAlsoAppliesAfterUpdates) {
  HeapWithStorage h(10);
  ASSERT_TRUE(h.heap.push(8, 5.0F));
  ASSERT_TRUE(h.heap.push(2, 1.0F));
  ASSERT_TRUE(h.heap.push(6, 3.0F));
  ASSERT_TRUE(h.heap.decrease(8, 1.0F));  // now ties with key 2, which is lower: 2 stays first
  EXPECT_EQ(h.heap.top().key, 2u);
  ASSERT_TRUE(h.heap.update(6, 1.0F));
  std::vector<Key> popped;
  while (auto node = h.heap.pop()) popped.push_back(node->key);
  EXPECT_EQ(popped, (std::vector<Key>{2, 6, 8}));
}

TEST(BoundedIndexHeapTest, DecreaseUpdateAndPushOrDecrease) {
  HeapWithStorage h(10);
  Heap& heap = h.heap;
  for (Key k = 0; k < 5; ++k) ASSERT_TRUE(heap.push(k, 10.0F + static_cast<float>(k)));
  EXPECT_TRUE(heap.decrease(4, 1.0F));
  EXPECT_EQ(heap.top().key, 4u);
  EXPECT_FALSE(heap.decrease(4, 1.0F)) << "not strictly lower";
  EXPECT_FALSE(heap.decrease(4, 5.0F)) << "higher";
  EXPECT_EQ(heap.priority(4), 1.0F);
  EXPECT_FALSE(heap.decrease(9, 0.0F)) << "not queued";
  EXPECT_FALSE(heap.update(9, 0.0F)) << "not queued";
  EXPECT_TRUE(heap.update(4, 50.0F)) << "update may raise";
  EXPECT_EQ(heap.top().key, 0u);
  EXPECT_TRUE(heap.push_or_decrease(7, 0.5F)) << "absent: inserted";
  EXPECT_EQ(heap.top().key, 7u);
  EXPECT_FALSE(heap.push_or_decrease(7, 0.6F)) << "queued with a lower priority: unchanged";
  EXPECT_TRUE(heap.push_or_decrease(7, 0.25F));
  EXPECT_EQ(heap.priority(7), 0.25F);
  EXPECT_FALSE(heap.push_or_decrease(10, 0.0F)) << "out of range";
}

TEST(BoundedIndexHeapTest, EraseAnywhere) {
  HeapWithStorage h(16);
  Heap& heap = h.heap;
  for (Key k = 0; k < 16; ++k) ASSERT_TRUE(heap.push(k, static_cast<float>((k * 7) % 16)));
  EXPECT_TRUE(heap.erase(5));
  EXPECT_TRUE(heap.erase(0));
  EXPECT_FALSE(heap.erase(0));
  EXPECT_FALSE(heap.erase(99));
  EXPECT_EQ(heap.size(), 14u);
  const auto popped = drain(heap);
  ASSERT_EQ(popped.size(), 14u);
  EXPECT_TRUE(std::is_sorted(popped.begin(), popped.end()));
  for (const auto& [priority, key] : popped) EXPECT_TRUE(key != 5 && key != 0);
}

TEST(BoundedIndexHeapTest, ClearForgetsOnlyQueuedKeysAndAllowsReuse) {
  HeapWithStorage h(100);
  Heap& heap = h.heap;
  for (Key k = 0; k < 100; k += 3) ASSERT_TRUE(heap.push(k, 1.0F));
  heap.clear();
  EXPECT_TRUE(heap.empty());
  for (Key k = 0; k < 100; ++k) ASSERT_FALSE(heap.contains(k));
  for (Key k = 0; k < 100; ++k) ASSERT_TRUE(heap.push(k, static_cast<float>(100 - k)));
  EXPECT_EQ(heap.top().key, 99u);
}

// Interleaved random push / pop / decrease / update / erase against std::priority_queue of
// (priority, key) with lazy deletion, which pops in exactly the documented order.
TEST(BoundedIndexHeapTest, MatchesAReferenceModelOverRandomOperations) {
  constexpr Key kKeys = 500;
  HeapWithStorage h(kKeys);
  Heap& heap = h.heap;
  std::map<Key, float> queued;  // the model's truth
  using Entry = std::pair<float, Key>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> reference;  // may hold stale entries
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<int> priority_steps(0, 40);  // coarse: many ties
  const auto random_priority = [&] { return static_cast<float>(priority_steps(rng)) * 0.25F; };
  const auto model_pop = [&]() -> std::optional<Entry> {
    while (!reference.empty()) {
      const Entry e = reference.top();
      reference.pop();
      auto it = queued.find(e.second);
      if (it != queued.end() && it->second == e.first) {
        queued.erase(it);
        return e;
      }
    }
    return std::nullopt;
  };

  for (int step = 0; step < 200'000; ++step) {
    const Key key = static_cast<Key>(rng() % kKeys);
    const float priority = random_priority();
    switch (rng() % 5) {
      case 0:
      case 1: {
        const bool expected = queued.count(key) == 0;
        ASSERT_EQ(heap.push(key, priority), expected);
        if (expected) {
          queued[key] = priority;
          reference.emplace(priority, key);
        }
        break;
      }
      case 2: {
        const auto it = queued.find(key);
        const bool expected = it != queued.end() && priority < it->second;
        ASSERT_EQ(heap.decrease(key, priority), expected);
        if (expected) {
          it->second = priority;
          reference.emplace(priority, key);
        }
        break;
      }
      case 3: {
        const auto it = queued.find(key);
        ASSERT_EQ(heap.update(key, priority), it != queued.end());
        if (it != queued.end()) {
          it->second = priority;
          reference.emplace(priority, key);
        }
        if (rng() % 4 == 0) {
          ASSERT_EQ(heap.erase(key), queued.erase(key) == 1);
        }
        break;
      }
      default: {
        const auto expected = model_pop();
        const auto got = heap.pop();
        ASSERT_EQ(got.has_value(), expected.has_value());
        if (got) {
          ASSERT_EQ(got->priority, expected->first) << "step " << step;
          ASSERT_EQ(got->key, expected->second) << "step " << step;
        }
      }
    }
    ASSERT_EQ(heap.size(), queued.size());
  }
  for (const auto& [key, priority] : queued) {
    ASSERT_TRUE(heap.contains(key));
    ASSERT_EQ(heap.priority(key), priority);
  }
  while (auto expected = model_pop()) {
    const auto got = heap.pop();
    ASSERT_TRUE(got.has_value());
    ASSERT_EQ(got->key, expected->second);
  }
  EXPECT_TRUE(heap.empty());
}

// Dijkstra over a random-cost grid with the heap as the open list (push_or_decrease), against
// a quadratic Dijkstra with no heap at all. Exercises decrease-key the way a planner does.
TEST(BoundedIndexHeapTest, DijkstraOnAGridMatchesAQuadraticDijkstra) {
  constexpr int kWidth = 40;
  constexpr int kHeight = 30;
  constexpr int kCells = kWidth * kHeight;
  std::mt19937_64 rng(1);
  std::vector<bool> blocked(kCells);
  for (int c = 1; c < kCells; ++c) blocked[c] = rng() % 6 == 0;
  // Costs per directed edge (not per cell), so cells are often reached first by a worse path
  // and then improved: decrease-key.
  const auto edge_cost = [](int from, int to) {
    return 1 + static_cast<std::uint32_t>((from * 7919 + to * 104729) % 9);
  };
  const auto neighbours = [&](int cell, auto&& visit) {
    const int x = cell % kWidth;
    const int y = cell / kWidth;
    if (x > 0) visit(cell - 1);
    if (x + 1 < kWidth) visit(cell + 1);
    if (y > 0) visit(cell - kWidth);
    if (y + 1 < kHeight) visit(cell + kWidth);
  };
  constexpr std::uint32_t kInfinity = std::numeric_limits<std::uint32_t>::max();

  // Heap-based.
  BudgetArena arena("dijkstra", BoundedIndexHeap<std::uint32_t>::storage_bytes(kCells) + 64);
  BoundedIndexHeap<std::uint32_t> open;  // declared after its arena: destroyed before it
  ASSERT_TRUE(open.init(kCells, &arena).ok());
  std::vector<std::uint32_t> dist(kCells, kInfinity);
  dist[0] = 0;
  ASSERT_TRUE(open.push(0, 0));
  int decreases = 0;
  while (auto node = open.pop()) {
    neighbours(static_cast<int>(node->key), [&](int next) {
      if (blocked[next]) return;
      const std::uint32_t candidate = node->priority + edge_cost(static_cast<int>(node->key), next);
      if (candidate < dist[next]) {
        if (open.contains(static_cast<Key>(next))) ++decreases;
        dist[next] = candidate;
        ASSERT_TRUE(open.push_or_decrease(static_cast<Key>(next), candidate));
      }
    });
  }
  EXPECT_GT(decreases, 0) << "the grid should exercise decrease-key";

  // Quadratic reference.
  std::vector<std::uint32_t> ref(kCells, kInfinity);
  std::vector<bool> done(kCells, false);
  ref[0] = 0;
  for (;;) {
    int best = -1;
    for (int c = 0; c < kCells; ++c) {
      if (!done[c] && ref[c] != kInfinity && (best < 0 || ref[c] < ref[best])) best = c;
    }
    if (best < 0) break;
    done[best] = true;
    neighbours(best, [&](int next) {
      const std::uint32_t candidate = ref[best] + edge_cost(best, next);
      if (!blocked[next] && candidate < ref[next]) ref[next] = candidate;
    });
  }
  EXPECT_EQ(dist, ref);
}

TEST(BoundedIndexHeapTest, MaxHeapThroughTheComparator) {
  std::array<BoundedIndexHeap<int, std::greater<int>>::Node, 4> nodes{};
  std::array<Key, 4> positions{};
  BoundedIndexHeap<int, std::greater<int>> heap;
  ASSERT_TRUE(heap.init(nodes, positions).ok());
  ASSERT_TRUE(heap.push(0, 1));
  ASSERT_TRUE(heap.push(1, 5));
  ASSERT_TRUE(heap.push(2, 5));
  ASSERT_TRUE(heap.push(3, 3));
  EXPECT_EQ(heap.pop()->key, 1u) << "equal priorities: lower key first";
  EXPECT_EQ(heap.pop()->key, 2u);
  EXPECT_EQ(heap.pop()->key, 3u);
  EXPECT_TRUE(heap.decrease(0, 7)) << "\"decrease\" means earlier under the comparator";
  EXPECT_EQ(heap.pop()->priority, 7);
}

TEST(BoundedIndexHeapTest, MoveTransfersStorage) {
  BudgetArena arena("heap", 4096);
  Heap a;
  ASSERT_TRUE(a.init(10, &arena).ok());
  ASSERT_TRUE(a.push(3, 1.0F));
  Heap b(std::move(a));
  EXPECT_EQ(a.capacity(), 0u);  // NOLINT(bugprone-use-after-move): documented empty state
  EXPECT_EQ(b.capacity(), 10u);
  EXPECT_TRUE(b.contains(3));
  Heap c;
  c = std::move(b);
  EXPECT_EQ(c.pop()->key, 3u);
}

}  // namespace
}  // namespace sen3bot::mem
