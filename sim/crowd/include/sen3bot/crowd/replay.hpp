#pragma once
// Replays a Recording as walkers: each track's position and velocity at any time, on a cubic
// Hermite curve through every annotation with a continuous velocity, no faster between two
// evenly spaced annotations than 1.5 times the fastest of the three annotated speeds around
// them, and no overshoot where a person stops (the tangents are explained in replay.cpp).
// Queries never allocate (the curves are built once, in the constructor), so a simulated world
// can ask for every walker on each tick.
#include <cstddef>
#include <span>
#include <vector>

#include "sen3bot/crowd/recording.hpp"

namespace sen3bot::crowd {

struct WalkerState {
  bool visible = false;  // the track's walk covers the time
  Point2D position;      // zero while not visible
  Point2D velocity_m_s;
};

class Replay {
 public:
  // Takes a recording as parse_recording() builds it (each track's times strictly increasing).
  explicit Replay(Recording recording);

  [[nodiscard]] const Recording& recording() const noexcept { return recording_; }
  [[nodiscard]] std::size_t track_count() const noexcept { return recording_.tracks.size(); }

  // Track `track` at time_s: visible from its first annotation to its last, both included, and
  // at an annotation's time exactly where the file puts it. A cursor per track makes queries at
  // non-decreasing times O(1) amortised; an earlier time costs a binary search. An unknown
  // track, or a NaN time, is not visible.
  [[nodiscard]] WalkerState state_at(std::size_t track, double time_s) noexcept;
  // Every track at time_s: out[i] is track i, for the first min(out.size(), track_count()).
  void states_at(double time_s, std::span<WalkerState> out) noexcept;

 private:
  struct Curve {
    std::vector<Point2D> tangent_m_s;  // velocity at each annotation
    std::size_t cursor = 0;            // the interval last queried
  };

  Recording recording_;
  std::vector<Curve> curves_;  // one per track
};

}  // namespace sen3bot::crowd
