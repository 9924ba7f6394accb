#pragma once
// The simulated world as the LMS200 emulator's RangeSource: ranges from World::scan() at the
// sensor pose set from outside, "nothing hit" as +infinity (the emulator's convention).
// With advance_movers, each scan first moves the scripted movers to the scan's time.
#include <span>

#include "sen3bot/sim/lms200/emulator.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::world {

class WorldRangeSource final : public lms200::RangeSource {
 public:
  // world must outlive this; it is not locked, so only the emulator's thread may touch it.
  explicit WorldRangeSource(World& world, bool advance_movers = true) noexcept
      : world_(world), advance_movers_(advance_movers) {}
  void ranges(hal::Nanos t, const lms200::ScanGeometry& geometry, std::span<float> out_m) override;

 private:
  World& world_;
  bool advance_movers_;
};

}  // namespace sen3bot::world
