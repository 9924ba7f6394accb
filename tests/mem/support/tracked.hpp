#pragma once
// Tracked: an element type that counts its constructions, destructions, copies and moves, and
// notices use of a dead object, to test that containers manage lifetimes exactly.
#include <gtest/gtest.h>

#include <cstdint>

namespace sen3bot::mem::testing {

struct Tracked {
  static constexpr std::uint32_t kAlive = 0xA11FE;
  static inline int constructed = 0;
  static inline int destroyed = 0;
  static inline int copies = 0;  // copy constructions and copy assignments
  static inline int moves = 0;   // move constructions and move assignments
  static inline int misuse = 0;  // destroying, assigning or copying an object that is not alive

  static int live() { return constructed - destroyed; }
  static void reset() { constructed = destroyed = copies = moves = misuse = 0; }

  Tracked() : Tracked(0) {}
  explicit Tracked(int v) : value(v) { ++constructed; }
  Tracked(const Tracked& other) : value(other.value) {
    check(other);
    ++constructed;
    ++copies;
  }
  Tracked(Tracked&& other) noexcept : value(other.value) {
    check(other);
    other.value = -1;
    ++constructed;
    ++moves;
  }
  Tracked& operator=(const Tracked& other) {
    check(*this);
    check(other);
    value = other.value;
    ++copies;
    return *this;
  }
  Tracked& operator=(Tracked&& other) noexcept {
    check(*this);
    check(other);
    value = other.value;
    other.value = -1;
    ++moves;
    return *this;
  }
  ~Tracked() {
    check(*this);
    alive = 0;
    ++destroyed;
  }

  friend bool operator==(const Tracked& a, const Tracked& b) { return a.value == b.value; }
  friend bool operator<(const Tracked& a, const Tracked& b) { return a.value < b.value; }

  int value = 0;
  std::uint32_t alive = kAlive;

 private:
  static void check(const Tracked& t) {
    if (t.alive != kAlive) ++misuse;
  }
};

// Resets the counters before each test and checks after it that every Tracked constructed was
// destroyed exactly once and no dead object was touched.
class TrackedTest : public ::testing::Test {
 protected:
  void SetUp() override { Tracked::reset(); }
  void TearDown() override {
    EXPECT_EQ(Tracked::live(), 0) << "leaked or double-destroyed elements";
    EXPECT_EQ(Tracked::misuse, 0) << "a dead element was used";
  }
};

}  // namespace sen3bot::mem::testing
