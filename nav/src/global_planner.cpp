#include "sen3bot/nav/global_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {
namespace {

// Neighbour order is fixed (part of the deterministic tie-breaking): E, N, W, S, NE, NW, SW, SE.
constexpr int kDc[8] = {1, 0, -1, 0, 1, -1, -1, 1};
constexpr int kDr[8] = {0, 1, 0, -1, 1, 1, -1, -1};
constexpr float kSqrt2 = 1.41421356237309504880f;
constexpr std::uint8_t kStartDir = 255;
constexpr std::uint8_t kUnseen = 0;
constexpr std::uint8_t kOpen = 1;
constexpr std::uint8_t kClosed = 2;

}  // namespace

std::size_t GlobalPlanner::storage_bytes(const GlobalPlannerConfig& c) noexcept {
  return mem::BoundedIndexHeap<Priority>::storage_bytes(c.max_cells) +
         c.max_cells * (sizeof(float) + 1 + 2 + 1 + 2) + c.max_waypoints * sizeof(GridCell) + 256;
}

Status GlobalPlanner::init(const GlobalPlannerConfig& config, std::pmr::memory_resource& resource) {
  if (config.max_cells == 0 || config.max_waypoints >= 65535 || config.waypoint_reach_cells < 0) {
    return Error::format(Errc::config, "global planner: max_cells must be > 0, max_waypoints < 65535");
  }
  config_ = config;
  blocked_cost_ = config.blocked_cost;
  return guarded("global planner", [&]() -> Status {
    // Caller-owned storage: the heap then never hands memory back to the arena, so the
    // planner may outlive its arena's bookkeeping (destruction order does not matter).
    using Heap = mem::BoundedIndexHeap<Priority>;
    auto nodes = allocate_array<Heap::Node>(resource, config.max_cells);
    auto positions = allocate_array<Heap::Key>(resource, config.max_cells);
    if (Status s = open_.init(nodes, positions); !s) return s;
    g_ = allocate_array<float>(resource, config.max_cells);
    parent_dir_ = allocate_array<std::uint8_t>(resource, config.max_cells);
    stage_ = allocate_array<std::uint16_t>(resource, config.max_cells);
    state_ = allocate_array<std::uint8_t>(resource, config.max_cells);
    reach_ = allocate_array<std::uint16_t>(resource, config.max_cells);
    waypoint_cells_ = allocate_array<GridCell>(resource, config.max_waypoints);
    return Status::success();
  });
}

bool GlobalPlanner::passable(std::uint8_t cost) const noexcept {
  if (cost == kNoInformationCost) return config_.allow_unknown;
  return cost < blocked_cost_;
}

bool GlobalPlanner::enterable(std::uint8_t from_cost, std::uint8_t cost) const noexcept {
  if (passable(cost)) return true;
  // The escape rule: from a cell inside the clearance band (blocked_cost .. 252), steps that
  // do not climb the inflation gradient stay allowed, so a robot that ended up close to
  // something can still plan its way out.
  return cost < kInscribedCost && from_cost < kInscribedCost && !passable(from_cost) && cost <= from_cost;
}

double GlobalPlanner::path_cost(const Costmap2D& costmap, std::span<const GridCell> path) const noexcept {
  constexpr double kBlocked = std::numeric_limits<double>::infinity();
  if (path.empty()) return kBlocked;
  double total = 0.0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (!costmap.in_bounds(path[i].col, path[i].row)) return kBlocked;
    if (i == 0) continue;
    const int dc = path[i].col - path[i - 1].col;
    const int dr = path[i].row - path[i - 1].row;
    if (dc < -1 || dc > 1 || dr < -1 || dr > 1 || (dc == 0 && dr == 0)) return kBlocked;  // not a cell path
    const std::uint8_t cost = costmap.at(path[i].col, path[i].row);
    if (!enterable(costmap.at(path[i - 1].col, path[i - 1].row), cost)) return kBlocked;
    total += step_cost(cost, dc != 0 && dr != 0);
  }
  return total;
}

float GlobalPlanner::step_cost(std::uint8_t cost, bool diagonal) const noexcept {
  const float length = diagonal ? kSqrt2 : 1.0f;
  if (config_.unit_cost) return length;
  const float c = cost == kNoInformationCost ? static_cast<float>(kMaxNonObstacleCost) : static_cast<float>(cost);
  return length * (1.0f + static_cast<float>(config_.cost_weight) * c / static_cast<float>(kMaxNonObstacleCost));
}

PlanResult GlobalPlanner::plan(const Costmap2D& costmap, GridCell start, GridCell goal,
                               std::span<const GridCell> waypoints, std::span<GridCell> path) noexcept {
  PlanResult result;
  const int w = costmap.width();
  const int h = costmap.height();
  const std::size_t n = costmap.size();
  if (n > config_.max_cells || waypoints.size() > config_.max_waypoints) {
    result.status = PlanStatus::too_large;
    return result;
  }
  if (!costmap.in_bounds(start.col, start.row)) {
    result.status = PlanStatus::start_outside;
    return result;
  }
  if (!costmap.in_bounds(goal.col, goal.row)) {
    result.status = PlanStatus::goal_outside;
    return result;
  }
  // A goal inside the clearance band (but not in collision) lowers the bar for this plan to
  // just above the goal's cost; a start inside it plans out by the escape rule.
  blocked_cost_ = config_.blocked_cost;
  const std::uint8_t goal_cost = costmap.at(goal.col, goal.row);
  if (!passable(goal_cost) && goal_cost < kInscribedCost) blocked_cost_ = static_cast<std::uint8_t>(goal_cost + 1);
  const std::uint8_t start_cost = costmap.at(start.col, start.row);
  if (!passable(start_cost) && !(start_cost < kInscribedCost)) {
    result.status = PlanStatus::start_blocked;
    return result;
  }
  if (!passable(goal_cost)) {
    result.status = PlanStatus::goal_blocked;
    return result;
  }

  open_.clear();
  std::fill_n(state_.begin(), n, kUnseen);
  std::fill_n(reach_.begin(), n, std::uint16_t{0});
  const auto wp_count = static_cast<std::uint16_t>(waypoints.size());
  const int reach = config_.waypoint_reach_cells;
  for (std::uint16_t k = 0; k < wp_count; ++k) {
    waypoint_cells_[k] = waypoints[k];
    for (int r = waypoints[k].row - reach; r <= waypoints[k].row + reach; ++r) {
      for (int c = waypoints[k].col - reach; c <= waypoints[k].col + reach; ++c) {
        if (costmap.in_bounds(c, r)) {
          std::uint16_t& slot = reach_[costmap.index(c, r)];
          slot = std::max<std::uint16_t>(slot, static_cast<std::uint16_t>(k + 1));
        }
      }
    }
  }
  const float attraction_cells = static_cast<float>(config_.waypoint_attraction_m / costmap.resolution_m());
  const float wp_weight = static_cast<float>(config_.waypoint_weight);
  const auto heuristic = [&](int c, int r, std::uint16_t stage) {
    const float hg = std::hypot(static_cast<float>(c - goal.col), static_cast<float>(r - goal.row));
    if (stage >= wp_count) return hg;
    const GridCell wp = waypoint_cells_[stage];
    const float dw = std::hypot(static_cast<float>(c - wp.col), static_cast<float>(r - wp.row));
    return dw <= attraction_cells ? hg + wp_weight * dw : hg;
  };
  const auto advance = [&](std::uint16_t stage, std::size_t cell) {
    return std::max(stage, reach_[cell]);
  };
  const auto rank = [&](std::uint16_t stage) { return static_cast<std::uint16_t>(config_.max_waypoints - stage); };

  const std::size_t start_index = costmap.index(start.col, start.row);
  const std::size_t goal_index = costmap.index(goal.col, goal.row);
  const std::uint16_t start_stage = advance(0, start_index);
  g_[start_index] = 0.0f;
  stage_[start_index] = start_stage;
  parent_dir_[start_index] = kStartDir;
  state_[start_index] = kOpen;
  (void)open_.push(static_cast<std::uint32_t>(start_index), {rank(start_stage), heuristic(start.col, start.row, start_stage)});

  const std::size_t cap = config_.max_expansions == 0 ? n : config_.max_expansions;
  bool found = false;
  while (!open_.empty()) {
    const auto node = *open_.pop();
    const std::size_t cur = node.key;
    state_[cur] = kClosed;
    ++result.expansions;
    if (cur == goal_index) {
      found = true;
      break;
    }
    if (result.expansions >= cap) {
      result.status = PlanStatus::expansion_cap;
      return result;
    }
    const int cc = static_cast<int>(cur % static_cast<std::size_t>(w));
    const int cr = static_cast<int>(cur / static_cast<std::size_t>(w));
    const float g_cur = g_[cur];
    const std::uint16_t stage_cur = stage_[cur];
    const std::uint8_t cur_cost = costmap.at(cc, cr);
    for (std::uint8_t dir = 0; dir < 8; ++dir) {
      const int nc = cc + kDc[dir];
      const int nr = cr + kDr[dir];
      if (nc < 0 || nr < 0 || nc >= w || nr >= h) continue;
      const std::size_t next = costmap.index(nc, nr);
      if (state_[next] == kClosed) continue;
      const std::uint8_t cost = costmap.at(nc, nr);
      if (!enterable(cur_cost, cost)) continue;
      const bool diagonal = dir >= 4;
      if (diagonal && (!enterable(cur_cost, costmap.at(nc, cr)) || !enterable(cur_cost, costmap.at(cc, nr)))) continue;  // no corner cutting
      const float g_new = g_cur + step_cost(cost, diagonal);
      const std::uint16_t stage_new = advance(stage_cur, next);
      if (state_[next] == kOpen) {
        const bool better = stage_new > stage_[next] || (stage_new == stage_[next] && g_new < g_[next]);
        if (!better) continue;
      }
      g_[next] = g_new;
      stage_[next] = stage_new;
      parent_dir_[next] = dir;
      state_[next] = kOpen;
      const Priority priority{rank(stage_new), g_new + heuristic(nc, nr, stage_new)};
      if (!open_.update(static_cast<std::uint32_t>(next), priority)) {
        (void)open_.push(static_cast<std::uint32_t>(next), priority);
      }
    }
  }
  if (!found) {
    result.status = PlanStatus::no_path;
    return result;
  }
  // Walk back from the goal, then reverse in place.
  std::size_t count = 0;
  std::size_t at = goal_index;
  double length_cells = 0.0;
  for (;;) {
    if (count >= path.size()) {
      result.status = PlanStatus::path_too_long;
      return result;
    }
    const int c = static_cast<int>(at % static_cast<std::size_t>(w));
    const int r = static_cast<int>(at / static_cast<std::size_t>(w));
    path[count++] = {c, r};
    const std::uint8_t dir = parent_dir_[at];
    if (dir == kStartDir) break;
    length_cells += dir >= 4 ? 1.4142135623730951 : 1.0;
    at = costmap.index(c - kDc[dir], r - kDr[dir]);
  }
  std::reverse(path.begin(), path.begin() + static_cast<std::ptrdiff_t>(count));
  result.status = PlanStatus::ok;
  result.cells = count;
  result.length_m = length_cells * costmap.resolution_m();
  result.cost = g_[goal_index];
  result.waypoints_passed = stage_[goal_index];
  return result;
}

PlanResult GlobalPlanner::plan_world(const Costmap2D& costmap, Point2D start, Point2D goal,
                                     std::span<const Point2D> waypoints, std::span<GridCell> path) noexcept {
  GridCell s;
  GridCell g;
  PlanResult result;
  if (!costmap.world_to_cell(start.x_m, start.y_m, s.col, s.row)) {
    result.status = PlanStatus::start_outside;
    return result;
  }
  if (!costmap.world_to_cell(goal.x_m, goal.y_m, g.col, g.row)) {
    result.status = PlanStatus::goal_outside;
    return result;
  }
  if (waypoints.size() > config_.max_waypoints) {
    result.status = PlanStatus::too_large;
    return result;
  }
  // Waypoints off the costmap are dropped: they cannot be reached anyway.
  std::size_t kept = 0;
  GridCell* cells = waypoint_cells_.data();
  for (const Point2D& p : waypoints) {
    GridCell c;
    if (costmap.world_to_cell(p.x_m, p.y_m, c.col, c.row)) cells[kept++] = c;
  }
  // plan() copies waypoints into waypoint_cells_ front to back, so aliasing is safe.
  return plan(costmap, s, g, std::span<const GridCell>(cells, kept), path);
}

}  // namespace sen3bot::nav
