#include "view_task.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <new>

#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/sgp.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

namespace {

namespace json = sen3bot::json;
using view::Schema;

constexpr std::array<std::string_view, kViewChannels> kTopics = {
    "/map", "/costmap/global", "/costmap/local", "/scan",   "/tf",          "/plan",    "/safe_path",
    "/path/driven", "/dwa", "/people", "/camera/image", "/stats", "/mission"};
constexpr std::array<Schema, kViewChannels> kSchemas = {
    Schema::grid,           Schema::grid,           Schema::grid,          Schema::laser_scan, Schema::frame_transform,
    Schema::poses_in_frame, Schema::scene_update,   Schema::poses_in_frame, Schema::poses_in_frame, Schema::scene_update,
    Schema::compressed_image, Schema::task_stats,   Schema::mission};

constexpr std::size_t kMaxPlanPoses = 256;      // the plan is thinned to this many
constexpr std::size_t kMaxSafePathPoints = 512;
constexpr std::size_t kMaxCurveSegments = 2048;  // the safe curve's outline, as a line list
constexpr std::size_t kDrivenPoses = 512;
constexpr std::size_t kRolloutPoses = 16;
constexpr std::size_t kCagePoints = 24;
constexpr std::size_t kMaxSceneEntities = msg::People::kMax + msg::MovingObstacles::kMax;
constexpr std::size_t kJpegBytes = 96 * 1024;
constexpr std::size_t kSmallChannelBytes = 16 * 1024;

std::size_t base64_size(std::size_t bytes) { return (bytes + 2) / 3 * 4; }

// Millimetres and tenths of a milliradian: short numbers on the wire, finer than any sensor.
double mm(double v) { return std::round(v * 1000.0) / 1000.0; }
double rad(double v) { return std::round(v * 10000.0) / 10000.0; }
view::Pose2 pose2(double x, double y, double theta) { return {mm(x), mm(y), rad(theta)}; }

const char* safety_reason(std::uint32_t bit) {
  switch (bit) {
    case msg::kSafetyScanStale: return "scan_stale";
    case msg::kSafetyOdomStale: return "odometry_stale";
    case msg::kSafetyEstop: return "estop";
    case msg::kSafetyMotorsOff: return "motors_off";
    case msg::kSafetyLocalizationLost: return "localization_lost";
    case msg::kSafetyObstacle: return "obstacle";
    case msg::kSafetySlowed: return "slow_zone";
    case msg::kSafetyReverseCapped: return "reverse_capped";
    case msg::kSafetyMoverApproach: return "mover_approach";
    case msg::kSafetyCage: return "cage";
    case msg::kSafetyEstopChain: return "estop_chain";
    case msg::kSafetyBumper: return "bumper";
    case msg::kSafetyIoLost: return "io_lost";
    case msg::kSafetyResetNeeded: return "reset_needed";
    case msg::kSafetySonar: return "sonar";
    case msg::kSafetySeparation: return "separation";
    default: return "other";
  }
}

}  // namespace

std::string_view topic_of(ViewChannel channel) noexcept { return kTopics[static_cast<std::size_t>(channel)]; }

std::string_view channel_key(ViewChannel channel) noexcept {
  constexpr std::array<std::string_view, kViewChannels> kKeys = {
      "map", "global_costmap", "local_costmap", "scan", "tf", "plan", "safe_path", "driven_path", "dwa", "people",
      "camera", "stats", "mission"};
  return kKeys[static_cast<std::size_t>(channel)];
}

// Everything a step writes besides the board, taken once from the arena.
struct ViewTask::Scratch {
  std::pmr::vector<std::uint8_t> map_cells;  // occupancy 0..100, 255 unknown
  tasks::Sample<msg::ScanMessage> scan;
  tasks::Sample<msg::PathMessage> path;
  tasks::Sample<msg::People> people;
  tasks::Sample<msg::MovingObstacles> movers;
  tasks::Sample<msg::CostmapSnapshot> local_costmap;
  std::array<view::Pose2, kMaxPlanPoses> plan{};
  std::array<view::Point2, kMaxSafePathPoints> safe_path{};
  std::pmr::vector<view::Point2> curve;  // pairs: the safe curve's zero set, traced once
  std::array<view::Pose2, kDrivenPoses> driven{};  // a ring
  std::size_t driven_head = 0;
  std::size_t driven_count = 0;
  std::array<view::Pose2, kDrivenPoses> driven_ordered{};
  std::array<view::Pose2, kRolloutPoses> rollout{};
  std::array<std::array<view::Point2, kCagePoints + 1>, msg::People::kMax> cages{};
  std::array<view::Line, msg::People::kMax> cage_lines{};
  std::array<view::Cylinder, kMaxSceneEntities> bodies{};
  std::array<view::Arrow, kMaxSceneEntities> arrows{};
  std::array<view::Text, msg::People::kMax> labels{};
  std::array<std::array<char, 24>, kMaxSceneEntities> ids{};
  std::array<std::array<char, 32>, msg::People::kMax> label_text{};
  std::array<view::Entity, kMaxSceneEntities> entities{};
  std::array<tasks::TaskStats, tasks::Scheduler::kMaxTasks> stats{};
  std::pmr::vector<std::uint8_t> jpeg;
  std::uint64_t camera_sequence = 0;
  view::JpegEncoder encoder;
  hal::Nanos unix_offset_ns = 0;

  Scratch(std::pmr::memory_resource& arena, view::JpegOptions jpeg_options)
      : map_cells(&arena), curve(&arena), jpeg(&arena), encoder(jpeg_options) {}
};

ViewTask::ViewTask(const ViewTaskConfig& config, const ViewSources& sources, view::Server* server) noexcept
    : config_(config), sources_(sources), server_(server) {
  board_channel_.fill(-1);
}

ViewTask::~ViewTask() {
  shutdown();
  if (scratch_ != nullptr) scratch_->~Scratch();  // its memory is the arena's
}

ViewTask::Shape ViewTask::shape_of(const ViewSources& s) noexcept {
  return {s.map != nullptr ? s.map->cell_count() : 0, s.map != nullptr && s.pose != nullptr && s.planner != nullptr,
          s.scan != nullptr, s.frames.pool != nullptr || s.frames.camera != nullptr};
}

std::size_t ViewTask::channel_specs(const ViewTaskConfig& config, const Shape& shape,
                                    std::span<view::ChannelSpec, kViewChannels> out) noexcept {
  std::size_t n = 0;
  const bool nav = shape.navigation;
  for (std::size_t i = 0; i < kViewChannels; ++i) {
    if (!(config.period_s[i] > 0)) continue;
    std::size_t bytes = 0;
    switch (static_cast<ViewChannel>(i)) {
      case ViewChannel::map:
      case ViewChannel::global_costmap: bytes = nav ? base64_size(shape.map_cells) + 1024 : 0; break;
      case ViewChannel::local_costmap: bytes = nav ? base64_size(msg::CostmapSnapshot::kMaxCells) + 1024 : 0; break;
      case ViewChannel::scan: bytes = shape.scan ? msg::ScanMessage::kMaxBeams * 12 + 1024 : 0; break;
      case ViewChannel::tf: bytes = nav ? 3 * 1024 : 0; break;
      case ViewChannel::plan: bytes = nav ? kMaxPlanPoses * 120 + 1024 : 0; break;
      case ViewChannel::safe_path: bytes = nav ? (kMaxSafePathPoints + 2 * kMaxCurveSegments) * 40 + 2048 : 0; break;
      case ViewChannel::driven_path: bytes = nav ? kDrivenPoses * 120 + 1024 : 0; break;
      case ViewChannel::dwa: bytes = nav ? kRolloutPoses * 120 + 1024 : 0; break;
      case ViewChannel::people: bytes = nav ? kMaxSceneEntities * 2600 + 1024 : 0; break;
      case ViewChannel::camera: bytes = shape.camera ? base64_size(kJpegBytes) + 512 : 0; break;
      case ViewChannel::stats: bytes = kSmallChannelBytes; break;
      case ViewChannel::mission: bytes = nav ? 4096 : 0; break;
    }
    if (bytes == 0) continue;
    out[n++] = {kTopics[i], kSchemas[i], bytes};
  }
  return n;
}

Status ViewTask::init(std::pmr::memory_resource& arena) {
  std::array<view::ChannelSpec, kViewChannels> specs{};
  const std::size_t n = channel_specs(config_, shape_of(sources_), specs);
  if (server_ == nullptr) {
    auto server = view::Server::create(config_.server, std::span(specs).first(n), arena);
    if (!server) return server.error();
    own_server_ = std::move(*server);
    server_ = own_server_.get();
  }
  std::array<bool, kViewChannels> served{};
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t i = 0; i < kViewChannels; ++i) served[i] = served[i] || specs[k].topic == kTopics[i];
  // The board's channels by topic: a server made elsewhere may serve them in another order.
  for (std::size_t i = 0; i < kViewChannels; ++i)
    for (std::size_t b = 0; b < server_->board().channel_count(); ++b)
      if (server_->board().spec(b).topic == kTopics[i] && config_.period_s[i] > 0 && served[i]) board_channel_[i] = static_cast<int>(b);
  std::pmr::polymorphic_allocator<Scratch> memory(&arena);
  scratch_ = memory.allocate(1);
  std::construct_at(scratch_, arena, view::JpegOptions{config_.camera_quality, config_.camera_max_width_px});
  Scratch& s = *scratch_;
  if (sources_.map != nullptr) {
    const auto& cells = sources_.map->cells();
    s.map_cells.resize(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i)
      s.map_cells[i] = cells[i] < 0 ? 255 : static_cast<std::uint8_t>(std::min<int>(cells[i], 100));
  }
  frames_ = sources_.frames.get();
  if (frames_ != nullptr) s.jpeg.resize(kJpegBytes);
  if (sources_.planner != nullptr && sources_.planner->sgp() != nullptr && sources_.map != nullptr) {
    // The safe curve's zero set inside its bounds and the map, on twice the map's grid.
    const nav::SupervisoryPlanner& sgp = *sources_.planner->sgp();
    const auto segments = nav::trace_curve(sgp.curve(), nav::intersect(sgp.bounds(), nav::map_extent(*sources_.map)),
                                           2.0 * sources_.map->resolution_m());
    s.curve.reserve(2 * std::min(segments.size(), kMaxCurveSegments));
    for (std::size_t k = 0; k < segments.size() && k < kMaxCurveSegments; ++k)
      for (const msg::Point2D& end : segments[k]) s.curve.push_back({mm(end.x_m), mm(end.y_m)});
  }
  s.unix_offset_ns = sources_.clock.unix_now_ns() - sources_.clock.now();
  start_ns_ = sources_.clock.now();
  next_ns_.fill(0);
  if (own_server_) {
    if (Status st = own_server_->start(); !st) return st;
  }
  return Status::success();
}

void ViewTask::shutdown() {
  if (own_server_) own_server_->stop();
}

bool ViewTask::write(std::size_t board_channel, hal::Nanos stamp, auto&& body) {
  view::ChannelBoard& board = server_->board();
  const std::span<char> space = board.space(board_channel);
  json::Writer w(space);
  body(w);
  auto text = w.finish();
  if (!text) {
    ++oversized_;
    board.discard(board_channel);
    return false;
  }
  board.commit(board_channel, text->size(), stamp);
  return true;
}

void ViewTask::step(const tasks::StepContext& context) {
  if (server_ == nullptr || scratch_ == nullptr) return;
  // Channels are due on the release grid, so a step that starts a little late does not push a
  // channel to the step after.
  const hal::Nanos now = context.release_ns;
  // The driven path grows every step, whether or not anyone watches.
  tasks::Sample<msg::PoseEstimate> pose;
  if (sources_.pose != nullptr && sources_.pose->read(pose) && pose.value.valid) {
    Scratch& s = *scratch_;
    const msg::Pose2D& p = pose.value.pose;
    const view::Pose2* last = s.driven_count > 0 ? &s.driven[(s.driven_head + kDrivenPoses - 1) % kDrivenPoses] : nullptr;
    if (last == nullptr || std::hypot(p.x_m - last->x_m, p.y_m - last->y_m) >= config_.driven_step_m) {
      s.driven[s.driven_head] = pose2(p.x_m, p.y_m, p.theta_rad);
      s.driven_head = (s.driven_head + 1) % kDrivenPoses;
      s.driven_count = std::min(s.driven_count + 1, kDrivenPoses);
    }
  }
  bool any = false;
  for (std::size_t i = 0; i < kViewChannels; ++i) {
    if (board_channel_[i] < 0 || now < next_ns_[i]) continue;
    const auto period = static_cast<hal::Nanos>(config_.period_s[i] * 1e9);
    next_ns_[i] = next_ns_[i] == 0 || next_ns_[i] + period <= now ? now + period : next_ns_[i] + period;
    if (encode(static_cast<ViewChannel>(i), now)) {
      server_->board().publish(static_cast<std::size_t>(board_channel_[i]));
      any = true;
    } else {
      server_->board().discard(static_cast<std::size_t>(board_channel_[i]));
    }
  }
  if (any) server_->notify();
}

bool ViewTask::encode(ViewChannel channel, hal::Nanos now) {
  Scratch& s = *scratch_;
  const std::size_t ch = static_cast<std::size_t>(board_channel_[static_cast<std::size_t>(channel)]);
  const hal::Nanos stamp = now + s.unix_offset_ns;
  switch (channel) {
    case ViewChannel::map: {
      const nav::OccupancyMap& m = *sources_.map;
      const view::GridView grid{s.map_cells, static_cast<std::uint32_t>(m.width()), static_cast<std::uint32_t>(m.height()),
                                m.resolution_m(), {m.origin_x_m(), m.origin_y_m()}, "occupancy"};
      return write(ch, stamp, [&](json::Writer& w) { view::write_grid(w, stamp, "map", grid); });
    }
    case ViewChannel::global_costmap: {
      const nav::Costmap2D& c = sources_.planner->costmap();
      const view::GridView grid{c.cells(), static_cast<std::uint32_t>(c.width()), static_cast<std::uint32_t>(c.height()),
                                c.resolution_m(), {c.origin_x_m(), c.origin_y_m()}, "cost"};
      return write(ch, stamp, [&](json::Writer& w) { view::write_grid(w, stamp, "map", grid); });
    }
    case ViewChannel::local_costmap: return encode_local_costmap(ch);
    case ViewChannel::scan: return encode_scan(ch);
    case ViewChannel::tf: return encode_tf(ch, stamp);
    case ViewChannel::plan: return encode_plan(ch);
    case ViewChannel::safe_path: return encode_safe_path(ch, stamp);
    case ViewChannel::driven_path: return encode_driven_path(ch, stamp);
    case ViewChannel::dwa: return encode_dwa(ch);
    case ViewChannel::people: return encode_people(ch, stamp);
    case ViewChannel::camera: return encode_camera(ch);
    case ViewChannel::stats: return encode_stats(ch, stamp, now);
    case ViewChannel::mission: return encode_mission(ch, stamp);
  }
  return false;
}

bool ViewTask::encode_local_costmap(std::size_t ch) {
  Scratch& s = *scratch_;
  if (!sources_.local_costmap->read(s.local_costmap)) return false;
  const msg::CostmapSnapshot& c = s.local_costmap.value;
  const view::GridView grid{std::span<const std::uint8_t>(c.cells.data(), static_cast<std::size_t>(c.columns) * c.rows),
                            c.columns, c.rows, c.resolution_m, {mm(c.origin_x_m), mm(c.origin_y_m)}, "cost"};
  const hal::Nanos at = s.local_costmap.stamp_ns + s.unix_offset_ns;
  return write(ch, at, [&](json::Writer& w) { view::write_grid(w, at, "map", grid); });
}

bool ViewTask::encode_scan(std::size_t ch) {
  Scratch& s = *scratch_;
  if (!sources_.scan->read(s.scan)) return false;
  const msg::ScanMessage& scan = s.scan.value;
  const hal::Nanos at = scan.stamp_ns + s.unix_offset_ns;
  return write(ch, at, [&](json::Writer& w) {
    view::write_laser_scan(w, at, "laser", scan.view().ranges_m, scan.angle_min_rad, scan.increment_rad,
                           scan.range_min_m, scan.range_max_m);
  });
}

bool ViewTask::encode_tf(std::size_t ch, hal::Nanos stamp) {
  tasks::Sample<msg::PoseEstimate> pose;
  tasks::Sample<msg::Odometry> odom;
  if (!sources_.pose->read(pose) || !pose.value.valid || !sources_.odometry->read(odom)) return false;
  // map -> odom so that map -> odom -> base_link is the estimate at the odometry's time.
  const msg::Pose2D base_in_odom{odom.value.x_m, odom.value.y_m, odom.value.theta_rad};
  const msg::Pose2D& base_in_map = pose.value.pose;
  const double dtheta = nav::normalize_angle(base_in_map.theta_rad - base_in_odom.theta_rad);
  const double c = std::cos(dtheta), sn = std::sin(dtheta);
  const msg::Pose2D odom_in_map{base_in_map.x_m - (c * base_in_odom.x_m - sn * base_in_odom.y_m),
                                base_in_map.y_m - (sn * base_in_odom.x_m + c * base_in_odom.y_m), dtheta};
  const msg::SensorMount& l = sources_.laser_mount;
  return write(ch, stamp, [&](json::Writer& w) {
           view::write_frame_transform(w, stamp, "map", "odom", pose2(odom_in_map.x_m, odom_in_map.y_m, odom_in_map.theta_rad));
         }) &&
         write(ch, stamp, [&](json::Writer& w) {
           view::write_frame_transform(w, stamp, "odom", "base_link", pose2(base_in_odom.x_m, base_in_odom.y_m, base_in_odom.theta_rad));
         }) &&
         write(ch, stamp, [&](json::Writer& w) {
           view::write_frame_transform(w, stamp, "base_link", "laser", {l.x_m, l.y_m, l.theta_rad});
         });
}

// The plan thinned to at most kMaxPlanPoses poses, each heading for the next; its end kept.
bool ViewTask::encode_plan(std::size_t ch) {
  Scratch& s = *scratch_;
  if (!sources_.path->read(s.path)) return false;
  const msg::PathMessage& path = s.path.value;
  const std::size_t count = std::min<std::size_t>(path.count, msg::PathMessage::kMaxPoints);
  const std::size_t step = count > kMaxPlanPoses ? (count + kMaxPlanPoses - 2) / (kMaxPlanPoses - 1) : 1;
  std::size_t n = 0;
  for (std::size_t i = 0; i < count && n < kMaxPlanPoses; i += step) {
    const std::size_t j = std::min(i + step, count - 1);
    const double heading = std::atan2(path.points[j].y_m - path.points[i].y_m, path.points[j].x_m - path.points[i].x_m);
    s.plan[n++] = pose2(path.points[i].x_m, path.points[i].y_m, heading);
  }
  if (count > 0 && n > 0 && (count - 1) % step != 0) {
    if (n == kMaxPlanPoses) --n;
    const double heading = s.plan[n > 0 ? n - 1 : 0].theta_rad;
    s.plan[n] = pose2(path.points[count - 1].x_m, path.points[count - 1].y_m, heading);
    ++n;
  }
  const hal::Nanos at = s.path.stamp_ns + s.unix_offset_ns;
  return write(ch, at, [&](json::Writer& w) { view::write_poses_in_frame(w, at, "map", std::span(s.plan).first(n)); });
}

bool ViewTask::encode_safe_path(std::size_t ch, hal::Nanos stamp) {
  Scratch& s = *scratch_;
  const std::span<const msg::Point2D> points = sources_.planner->safe_path();
  const std::size_t step = points.size() > kMaxSafePathPoints ? (points.size() + kMaxSafePathPoints - 1) / kMaxSafePathPoints : 1;
  std::size_t n = 0;
  for (std::size_t i = 0; i < points.size() && n < kMaxSafePathPoints; i += step)
    s.safe_path[n++] = {mm(points[i].x_m), mm(points[i].y_m)};
  const view::Line line{view::LineType::strip, std::span(s.safe_path).first(n), 0.04, {0.1, 0.6, 0.2, 0.9}};
  const view::Line curve{view::LineType::list, s.curve, 0.02, {0.2, 0.4, 0.9, 0.8}};
  const view::Entity entities[] = {{"waypoints", "map", 0, std::span(&line, n > 1 ? 1 : 0), {}, {}, {}},
                                   {"safe_curve", "map", 0, std::span(&curve, 1), {}, {}, {}}};
  const std::size_t count = s.curve.empty() ? 1 : 2;
  return write(ch, stamp, [&](json::Writer& w) { view::write_scene_update(w, stamp, true, std::span(entities).first(count)); });
}

bool ViewTask::encode_driven_path(std::size_t ch, hal::Nanos stamp) {
  Scratch& s = *scratch_;
  for (std::size_t i = 0; i < s.driven_count; ++i)
    s.driven_ordered[i] = s.driven[(s.driven_head + kDrivenPoses - s.driven_count + i) % kDrivenPoses];
  return write(ch, stamp, [&](json::Writer& w) {
    view::write_poses_in_frame(w, stamp, "map", std::span(s.driven_ordered).first(s.driven_count));
  });
}

bool ViewTask::encode_dwa(std::size_t ch) {
  Scratch& s = *scratch_;
  tasks::Sample<msg::PoseEstimate> pose;
  tasks::Sample<msg::VelocityCommand> request;
  if (!sources_.pose->read(pose) || !pose.value.valid || !sources_.request->read(request)) return false;
  // The chosen rollout is the arc of the requested (v, w) held for the DWA's simulated time.
  msg::Pose2D p = pose.value.pose;
  const double dt = sources_.rollout_s / static_cast<double>(kRolloutPoses - 1);
  for (std::size_t i = 0; i < kRolloutPoses; ++i) {
    s.rollout[i] = pose2(p.x_m, p.y_m, p.theta_rad);
    nav::advance_arc(p, request.value.v_m_s, request.value.w_rad_s, dt);
  }
  const hal::Nanos at = request.stamp_ns + s.unix_offset_ns;
  return write(ch, at, [&](json::Writer& w) { view::write_poses_in_frame(w, at, "map", s.rollout); });
}

// The people: each one's cage, body, heading and label; then the tracked movers.
bool ViewTask::encode_people(std::size_t ch, hal::Nanos stamp) {
  Scratch& s = *scratch_;
  std::size_t e = 0, body = 0, arrow = 0;
  if (sources_.people != nullptr && sources_.people->read(s.people)) {
    const msg::People& people = s.people.value;
    for (std::size_t i = 0; i < std::min<std::size_t>(people.count, msg::People::kMax); ++i) {
      const msg::TrackedPerson& p = people.items[i];
      std::array<view::Point2, kCagePoints + 1>& cage = s.cages[i];
      for (std::size_t k = 0; k < kCagePoints; ++k) {
        const double a = 2.0 * M_PI * static_cast<double>(k) / kCagePoints;
        cage[k] = {mm(p.x_m + p.cage_radius_m * std::cos(a)), mm(p.y_m + p.cage_radius_m * std::sin(a))};
      }
      // A hidden person (kept out of the sensors' view) is a guess: greyed, and labelled so.
      s.cage_lines[i] = {view::LineType::loop, std::span(cage).first(kCagePoints), 0.03,
                         p.hidden ? view::Color{0.5, 0.5, 0.5, 0.9} : view::Color{0.9, 0.2, 0.1, 0.9}};
      s.bodies[body] = {{mm(p.x_m), mm(p.y_m)}, std::max(0.2, p.width_m), 1.7,
                        p.hidden ? view::Color{0.6, 0.6, 0.6, 0.4} : view::Color{0.95, 0.6, 0.1, 0.8}};
      const double speed = std::hypot(p.vx_m_s, p.vy_m_s);
      const bool moving = speed > 0.05;
      if (moving) s.arrows[arrow] = {{mm(p.x_m), mm(p.y_m)}, rad(std::atan2(p.vy_m_s, p.vx_m_s)), mm(std::max(0.1, speed)), {0.9, 0.2, 0.1, 1.0}};
      std::snprintf(s.ids[e].data(), s.ids[e].size(), "person/%u", p.id);
      if (p.hidden)
        std::snprintf(s.label_text[i].data(), s.label_text[i].size(), "person %u hidden", p.id);
      else
        std::snprintf(s.label_text[i].data(), s.label_text[i].size(), "person %u", p.id);
      s.labels[i] = {{mm(p.x_m), mm(p.y_m + p.cage_radius_m)}, s.label_text[i].data(), 12.0, {0.1, 0.1, 0.1, 1.0}};
      s.entities[e] = {s.ids[e].data(), "map", 0, std::span(&s.cage_lines[i], 1), std::span(&s.bodies[body], 1),
                       std::span(&s.arrows[arrow], moving ? 1 : 0), std::span(&s.labels[i], 1)};
      ++e;
      ++body;
      arrow += moving ? 1 : 0;
    }
  }
  if (sources_.movers != nullptr && sources_.movers->read(s.movers)) {
    const msg::MovingObstacles& movers = s.movers.value;
    for (std::size_t i = 0; i < std::min<std::size_t>(movers.count, msg::MovingObstacles::kMax) && e < kMaxSceneEntities; ++i) {
      const msg::MovingObstacle& m = movers.items[i];
      s.bodies[body] = {{mm(m.x_m), mm(m.y_m)}, std::max(0.1, 2.0 * m.radius_m), 0.5, {0.5, 0.3, 0.8, 0.7}};
      const double speed = std::hypot(m.vx_m_s, m.vy_m_s);
      const bool moving = speed > 0.05;
      if (moving) s.arrows[arrow] = {{mm(m.x_m), mm(m.y_m)}, rad(std::atan2(m.vy_m_s, m.vx_m_s)), mm(std::max(0.1, speed)), {0.5, 0.3, 0.8, 1.0}};
      std::snprintf(s.ids[e].data(), s.ids[e].size(), "mover/%u", m.id);
      s.entities[e] = {s.ids[e].data(), "map", 0, {}, std::span(&s.bodies[body], 1),
                       std::span(&s.arrows[arrow], moving ? 1 : 0), {}};
      ++e;
      ++body;
      arrow += moving ? 1 : 0;
    }
  }
  return write(ch, stamp, [&](json::Writer& w) { view::write_scene_update(w, stamp, true, std::span(s.entities).first(e)); });
}

// The newest camera frame, once, as JPEG.
bool ViewTask::encode_camera(std::size_t ch) {
  Scratch& s = *scratch_;
  if (frames_ == nullptr) return false;
  camera::FramePool& frames = *frames_;
  if (frames.latest_sequence() == s.camera_sequence) return false;
  camera::FrameHandle frame = frames.acquire_latest();
  if (!frame) return false;
  const camera::FrameRef& f = frame.ref();
  s.camera_sequence = f.sequence;
  const view::Image image{f.data, f.width_px, f.height_px, f.stride_bytes,
                          f.format == camera::PixelFormat::bgr8 ? view::PixelLayout::bgr8 : view::PixelLayout::gray8};
  auto size = s.encoder.encode(image, s.jpeg);
  frame.release();
  if (!size) return false;
  const hal::Nanos at = f.decoded_ns + s.unix_offset_ns;
  return write(ch, at, [&](json::Writer& w) {
    view::write_compressed_image(w, at, "camera", std::span(s.jpeg).first(*size), "jpeg");
  });
}

bool ViewTask::encode_stats(std::size_t ch, hal::Nanos stamp, hal::Nanos now) {
  Scratch& s = *scratch_;
  const tasks::Scheduler& scheduler = sources_.scheduler;
  const std::size_t n = std::min(scheduler.task_count(), s.stats.size());
  for (std::size_t i = 0; i < n; ++i) s.stats[i] = scheduler.stats(i);
  const view::ServerCounters counters = server_->counters();
  return write(ch, stamp, [&](json::Writer& w) {
    w.begin_object();
    view::write_time(w, "timestamp", stamp);
    w.member_number("uptime_s", std::round(hal::to_seconds(now - start_ns_) * 10.0) / 10.0);
    w.key("tasks").begin_array();
    for (std::size_t i = 0; i < n; ++i) {
      const tasks::TaskStats& t = s.stats[i];
      w.begin_object().member("name", t.name).member("thread", t.thread);
      w.member_int64("period_us", t.period_us).member_int64("budget_us", t.budget_us);
      w.member_uint64("runs", t.runs).member_uint64("overruns", t.overruns);
      w.member_uint64("slips", t.slips).member_uint64("skips", t.skips);
      w.member_number("exec_mean_us", std::round(static_cast<double>(t.exec_mean_ns) / 100.0) / 10.0);
      w.member_number("exec_max_us", std::round(static_cast<double>(t.exec_max_ns) / 100.0) / 10.0);
      w.member_number("cpu_mean_us", std::round(static_cast<double>(t.cpu_mean_ns) / 100.0) / 10.0);
      w.member_number("cpu_max_us", std::round(static_cast<double>(t.cpu_max_ns) / 100.0) / 10.0);
      w.member_number("jitter_p99_us", std::round(static_cast<double>(t.jitter_p99_ns) / 100.0) / 10.0);
      w.end_object();
    }
    w.end_array();
    w.key("view").begin_object().member_uint64("clients", counters.clients).member_uint64("sent", counters.sent);
    w.member_uint64("dropped", counters.dropped).member_uint64("rejected", counters.rejected).end_object();
    w.end_object();
  });
}

bool ViewTask::encode_mission(std::size_t ch, hal::Nanos stamp) {
  tasks::Sample<msg::PoseEstimate> pose;
  tasks::Sample<msg::SafetyOutput> safety;
  tasks::Sample<msg::ControllerStatus> controller;
  const bool have_pose = sources_.pose != nullptr && sources_.pose->read(pose);
  const bool have_safety = sources_.safety != nullptr && sources_.safety->read(safety);
  const bool have_controller = sources_.controller != nullptr && sources_.controller->read(controller);
  const MissionTask* mission = sources_.mission;
  return write(ch, stamp, [&](json::Writer& w) {
    w.begin_object();
    view::write_time(w, "timestamp", stamp);
    w.member("state", mission != nullptr ? to_string(mission->report().state) : "fleet");
    w.member_uint32("goals_reached", mission != nullptr ? static_cast<std::uint32_t>(mission->report().goals_reached) : 0);
    w.member_uint32("goals_total", static_cast<std::uint32_t>(sources_.goal_count));
    w.key("goal");
    if (mission != nullptr && mission->current_goal() != nullptr)
      w.begin_object().member_number("x", mm(mission->current_goal()->x_m)).member_number("y", mm(mission->current_goal()->y_m)).end_object();
    else
      w.null();
    const msg::Pose2D p = have_pose ? pose.value.pose : msg::Pose2D{};
    w.key("pose").begin_object().member_number("x", mm(p.x_m)).member_number("y", mm(p.y_m));
    w.member_number("theta", rad(p.theta_rad)).end_object();
    w.member_bool("localized", have_pose && pose.value.valid).member_bool("lost", have_pose && pose.value.lost);
    w.member_number("v", have_safety ? mm(safety.value.command.v_m_s) : 0.0);
    w.member_number("w", have_safety ? rad(safety.value.command.w_rad_s) : 0.0);
    w.member("controller", have_controller ? (controller.value.formation ? "formation" : msg::to_string(controller.value.status)) : "none");
    w.key("safety").begin_array();
    if (have_safety)
      for (std::uint32_t bit = 1; bit != 0 && bit <= safety.value.reasons; bit <<= 1)
        if (safety.value.reasons & bit) w.string(safety_reason(bit));
    w.end_array();
    w.key("separation");
    if (have_safety && std::isfinite(safety.value.separation_cap_m_s))
      w.begin_object().member_number("cap", mm(safety.value.separation_cap_m_s)).member_number("gap", mm(safety.value.separation_gap_m))
          .member_number("approach", mm(safety.value.separation_approach_m_s)).end_object();
    else
      w.null();
    w.end_object();
  });
}

Status make_view(Wiring& w) {
  if (!w.config.view.enabled) return w.absent("needs a view section");
  const FirmwareConfig& config = w.config;
  ViewSources s{.scheduler = w.scheduler, .clock = w.board.clock()};
  if (w.shared.external_frames != nullptr) {
    w.takes("frames of a simulated camera");
    s.frames = FrameSource{w.shared.external_frames};
  } else if (w.uses("camera") != nullptr) {
    s.frames = FrameSource{nullptr, &w.shared.camera};
  }
  s.laser_mount = w.shared.laser_mount;
  s.scan = w.reads_if(config.devices.has_laser || config.navigation.enabled, &Topics::scan);
  if (config.navigation.enabled) {
    s.map = &w.shared.map;
    s.odometry = &w.reads(&Topics::odometry);
    s.pose = &w.reads(&Topics::pose);
    s.path = &w.reads(&Topics::path);
    s.request = &w.reads(&Topics::request);
    s.safety = &w.reads(&Topics::safety_output);
    s.controller = &w.reads(&Topics::controller_status);
    s.movers = &w.reads(&Topics::movers);
    s.people = w.reads_if(w.runs("people"), &Topics::people);
    const double local_s = config.view.task.period_s[static_cast<std::size_t>(ViewChannel::local_costmap)];
    s.local_costmap = w.reads_if(local_s > 0, &Topics::local_costmap);
    // Same thread as these rows: their costmap, safe path and report are read in place.
    s.planner = static_cast<const nav::PlannerTask*>(w.uses("planner"));
    s.mission = static_cast<const MissionTask*>(w.uses("mission"));
    s.goal_count = config.navigation.mission.goal_count;
    s.rollout_s = config.navigation.dwa.sim_time_s;
  }
  const int port = config.view.task.server.port;
  if (w.shared.external_view == nullptr)
    w.sends("the live view: HTTP and WebSocket on port " + std::to_string(port) + " (JSON and JPEG channels)");
  w.make<ViewTask>(config.view.task, s, w.shared.external_view);
  return Status::success();
}

}  // namespace sen3bot::firmware
