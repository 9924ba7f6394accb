#pragma once
// Global planner (GP): A* on a costmap, 8-connected without corner cutting, with the waypoint
// attraction of the thesis' Algorithm 1. All scratch memory is taken at init() for a maximum
// cell count; plan() allocates nothing.
//
// Cost of a step of length L (1 or sqrt 2 cells) into a cell of cost c:
//   L * (1 + cost_weight * c / 252)     (L alone with unit_cost)
// Cells with cost >= blocked_cost (253: inscribed and lethal) are impassable; 255 (unknown)
// is passable at cost 252 only with allow_unknown. A diagonal step needs both side cells free.
// A blocked_cost below 253 keeps plans out of gaps the local planner's padded footprint cannot
// pass (the clearance band blocked_cost..252). From a start inside that band the search may
// step to cells of equal or lower cost (downhill out of it, the escape rule); a goal inside
// it raises the bar to just above the goal's cost for that plan.
// The heuristic is the Euclidean distance in cells: admissible and consistent for these
// steps, so with no waypoints this is plain, optimal A*.
//
// Waypoint attraction, the rule chosen for Algorithm 1's "assign minimum values":
//  * every search state carries a stage k: how many waypoints, in order, its path has passed.
//    A waypoint is passed when a cell within waypoint_reach_cells (Chebyshev) of it is
//    entered; entering the reach of a LATER waypoint j also passes it (stage j + 1), so a
//    plan that joins the waypoint chain mid-way follows it from there.
//  * (i), (ii) passing a waypoint gives the state, and all its successors, the minimum
//    priority class: the open list orders by (stage descending, f ascending), so every state
//    that has passed more waypoints is expanded before any that has passed fewer. A cell's
//    stored state is replaced by a higher stage, or by a lower g at the same stage.
//  * (iii) once all waypoints are passed, h_WP = 0.
//  * (iv) otherwise f = g + h + h_WP with h_WP = waypoint_weight * distance to waypoint k,
//    counted only within waypoint_attraction_m of it (farther away it is 0, so far from the
//    waypoints the search is plain A*).
// Closed cells are never reopened (this keeps parent links acyclic). Ties in the open list go
// to the lower cell index, so the same inputs give a bit-identical path.
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/bounded_index_heap.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/nav/costmap.hpp"

namespace sen3bot::nav {

struct GridCell {
  std::int32_t col = 0;
  std::int32_t row = 0;
  friend bool operator==(const GridCell&, const GridCell&) = default;
};

struct GlobalPlannerConfig {
  std::size_t max_cells = 160 * 190;   // largest costmap planned on (sizes the scratch)
  std::size_t max_waypoints = 256;
  std::size_t max_expansions = 0;      // 0: the cell count of the costmap (every cell once)
  bool unit_cost = false;              // pure grid geometry: ignore costs below blocked_cost
  double cost_weight = 2.0;            // Smac 2D's cost_travel_multiplier
  std::uint8_t blocked_cost = kInscribedCost;
  bool allow_unknown = false;
  double waypoint_weight = 1.0;
  double waypoint_attraction_m = 1.5;
  int waypoint_reach_cells = 1;
};

using msg::PlanStatus;
using msg::to_string;

struct PlanResult {
  PlanStatus status = PlanStatus::no_path;
  std::size_t cells = 0;        // path cells written, start and goal included
  std::size_t expansions = 0;   // cells popped from the open list
  double length_m = 0.0;        // geometric length of the cell path
  double cost = 0.0;            // the search's g at the goal (cells)
  std::uint16_t waypoints_passed = 0;
  [[nodiscard]] bool ok() const noexcept { return status == PlanStatus::ok; }
};

class GlobalPlanner {
 public:
  Status init(const GlobalPlannerConfig& config, std::pmr::memory_resource& resource);
  // Bytes init() takes for a configuration (for sizing the arena).
  static std::size_t storage_bytes(const GlobalPlannerConfig& config) noexcept;

  // Plans from start to goal; the cell path (start first) goes to path.
  PlanResult plan(const Costmap2D& costmap, GridCell start, GridCell goal, std::span<const GridCell> waypoints,
                  std::span<GridCell> path) noexcept;
  // The same in map-frame metres.
  PlanResult plan_world(const Costmap2D& costmap, Point2D start, Point2D goal, std::span<const Point2D> waypoints,
                        std::span<GridCell> path) noexcept;

  // The search's cost (in cells) of following a cell path from its first cell to its last,
  // on this costmap; infinity when a step is not 8-adjacent, leaves the costmap or enters a
  // cell the search could not (blocked, with the same escape rule). Used to compare a kept
  // plan with a new one.
  [[nodiscard]] double path_cost(const Costmap2D& costmap, std::span<const GridCell> path) const noexcept;

  [[nodiscard]] const GlobalPlannerConfig& config() const noexcept { return config_; }

 private:
  struct Priority {
    std::uint16_t rank;  // max_waypoints - stage: lower first
    float f;
    friend bool operator<(const Priority& a, const Priority& b) noexcept {
      return a.rank != b.rank ? a.rank < b.rank : a.f < b.f;
    }
  };

  [[nodiscard]] bool passable(std::uint8_t cost) const noexcept;
  [[nodiscard]] bool enterable(std::uint8_t from_cost, std::uint8_t cost) const noexcept;
  [[nodiscard]] float step_cost(std::uint8_t cost, bool diagonal) const noexcept;

  GlobalPlannerConfig config_;
  std::uint8_t blocked_cost_ = kInscribedCost;  // this plan's bar (config_.blocked_cost, or raised for the goal)
  mem::BoundedIndexHeap<Priority> open_;
  std::span<float> g_;
  std::span<std::uint8_t> parent_dir_;  // 0..7 neighbour the cell was reached from, 255 start
  std::span<std::uint16_t> stage_;
  std::span<std::uint8_t> state_;       // 0 unseen, 1 open, 2 closed
  std::span<std::uint16_t> reach_;      // 1 + the highest waypoint whose reach covers the cell
  std::span<GridCell> waypoint_cells_;
};

}  // namespace sen3bot::nav
