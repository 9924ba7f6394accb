#include "sen3bot/view/foxglove.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sen3bot::view {
namespace {

constexpr hal::Nanos kNanosPerSecond = 1'000'000'000;

void write_vector3(json::Writer& out, std::string_view name, double x, double y, double z) noexcept {
  out.key(name).begin_object().member_number("x", x).member_number("y", y).member_number("z", z).end_object();
}

// A rotation about z by yaw.
void write_yaw(json::Writer& out, std::string_view name, double yaw) noexcept {
  const double half = 0.5 * yaw;
  out.key(name).begin_object();
  out.member_number("x", 0.0).member_number("y", 0.0);
  out.member_number("z", std::sin(half)).member_number("w", std::cos(half));
  out.end_object();
}

// The pose's object body (inside begin/end_object, so arrays of poses can use it too).
void pose_members(json::Writer& out, double x, double y, double z, double yaw) noexcept {
  write_vector3(out, "position", x, y, z);
  write_yaw(out, "orientation", yaw);
}

void write_pose(json::Writer& out, std::string_view name, double x, double y, double z, double yaw) noexcept {
  out.key(name).begin_object();
  pose_members(out, x, y, z, yaw);
  out.end_object();
}

void write_color(json::Writer& out, const Color& c) noexcept {
  out.key("color").begin_object();
  out.member_number("r", c.r).member_number("g", c.g).member_number("b", c.b).member_number("a", c.a);
  out.end_object();
}

void empty_array(json::Writer& out, std::string_view name) noexcept { out.key(name).begin_array().end_array(); }

void write_arrow(json::Writer& out, const Arrow& a) noexcept {
  out.begin_object();
  write_pose(out, "pose", a.from.x_m, a.from.y_m, 0.0, a.heading_rad);
  // A fixed shape scaled by the length, so a short arrow keeps the proportions of a long one.
  out.member_number("shaft_length", 0.8 * a.length_m);
  out.member_number("shaft_diameter", 0.1 * a.length_m);
  out.member_number("head_length", 0.2 * a.length_m);
  out.member_number("head_diameter", 0.2 * a.length_m);
  write_color(out, a.color);
  out.end_object();
}

void write_cylinder(json::Writer& out, const Cylinder& c) noexcept {
  out.begin_object();
  // The primitive's pose is its centre: lift it by half the height so it stands on the floor.
  write_pose(out, "pose", c.centre.x_m, c.centre.y_m, 0.5 * c.height_m, 0.0);
  write_vector3(out, "size", c.diameter_m, c.diameter_m, c.height_m);
  out.member_number("bottom_scale", 1.0);
  out.member_number("top_scale", 1.0);
  write_color(out, c.color);
  out.end_object();
}

void write_line(json::Writer& out, const Line& l) noexcept {
  out.begin_object();
  out.member_uint32("type", static_cast<std::uint32_t>(l.type));
  write_pose(out, "pose", 0.0, 0.0, 0.0, 0.0);
  out.member_number("thickness", l.thickness_m);
  out.member_bool("scale_invariant", false);
  out.key("points").begin_array();
  for (const Point2& p : l.points)
    out.begin_object().member_number("x", p.x_m).member_number("y", p.y_m).member_number("z", 0.0).end_object();
  out.end_array();
  write_color(out, l.color);
  empty_array(out, "colors");
  empty_array(out, "indices");
  out.end_object();
}

void write_text(json::Writer& out, const Text& t) noexcept {
  out.begin_object();
  write_pose(out, "pose", t.at.x_m, t.at.y_m, 0.0, 0.0);
  out.member_bool("billboard", true);
  out.member_number("font_size", t.font_size);
  out.member_bool("scale_invariant", true);
  write_color(out, t.color);
  out.member("text", t.text);
  out.end_object();
}

void write_entity(json::Writer& out, hal::Nanos stamp_ns, const Entity& e) noexcept {
  out.begin_object();
  write_time(out, "timestamp", stamp_ns);
  out.member("frame_id", e.frame_id);
  out.member("id", e.id);
  write_time(out, "lifetime", e.lifetime_ns);
  out.member_bool("frame_locked", false);
  empty_array(out, "metadata");
  out.key("arrows").begin_array();
  for (const Arrow& a : e.arrows) write_arrow(out, a);
  out.end_array();
  empty_array(out, "cubes");
  empty_array(out, "spheres");
  out.key("cylinders").begin_array();
  for (const Cylinder& c : e.cylinders) write_cylinder(out, c);
  out.end_array();
  out.key("lines").begin_array();
  for (const Line& l : e.lines) write_line(out, l);
  out.end_array();
  empty_array(out, "triangles");
  out.key("texts").begin_array();
  for (const Text& t : e.texts) write_text(out, t);
  out.end_array();
  empty_array(out, "models");
  out.end_object();
}

}  // namespace

void write_time(json::Writer& out, std::string_view name, hal::Nanos ns) noexcept {
  ns = std::max<hal::Nanos>(ns, 0);
  constexpr hal::Nanos kMaxSeconds = std::numeric_limits<std::uint32_t>::max();
  const hal::Nanos sec = std::min(ns / kNanosPerSecond, kMaxSeconds);
  const hal::Nanos nsec = sec == kMaxSeconds && ns / kNanosPerSecond > kMaxSeconds ? kNanosPerSecond - 1
                                                                                    : ns % kNanosPerSecond;
  out.key(name).begin_object();
  out.member_uint32("sec", static_cast<std::uint32_t>(sec));
  out.member_uint32("nsec", static_cast<std::uint32_t>(nsec));
  out.end_object();
}

void write_grid(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id, const GridView& grid) noexcept {
  // Whole rows only: a short cell span yields a smaller grid, never a ragged one.
  const std::size_t rows = grid.columns ? std::min<std::size_t>(grid.rows, grid.cells.size() / grid.columns) : 0;
  out.begin_object();
  write_time(out, "timestamp", stamp_ns);
  out.member("frame_id", frame_id);
  write_pose(out, "pose", grid.origin.x_m, grid.origin.y_m, 0.0, 0.0);
  out.member_uint32("column_count", grid.columns);
  out.key("cell_size").begin_object();
  out.member_number("x", grid.resolution_m).member_number("y", grid.resolution_m);
  out.end_object();
  out.member_uint32("row_stride", grid.columns);  // one byte per cell
  out.member_uint32("cell_stride", 1);
  out.key("fields").begin_array().begin_object();
  out.member("name", grid.field).member_uint32("offset", 0).member_uint32("type", 1);  // NumericType UINT8
  out.end_object().end_array();
  out.key("data").base64(grid.cells.first(rows * grid.columns));
  out.end_object();
}

void write_laser_scan(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id,
                      std::span<const float> ranges_m, double start_angle_rad, double increment_rad,
                      double range_min_m, double range_max_m) noexcept {
  const double end_angle =
      ranges_m.empty() ? start_angle_rad : start_angle_rad + increment_rad * static_cast<double>(ranges_m.size() - 1);
  out.begin_object();
  write_time(out, "timestamp", stamp_ns);
  out.member("frame_id", frame_id);
  write_pose(out, "pose", 0.0, 0.0, 0.0, 0.0);
  out.member_number("start_angle", start_angle_rad);
  out.member_number("end_angle", end_angle);
  out.key("ranges").begin_array();
  for (const float r : ranges_m) {
    // Written as comparisons that NaN fails, so NaN and infinity are "no return" too.
    const bool valid = static_cast<double>(r) >= range_min_m && static_cast<double>(r) < range_max_m;
    out.float32(valid ? r : 0.0f);
  }
  out.end_array();
  empty_array(out, "intensities");
  out.end_object();
}

void write_frame_transform(json::Writer& out, hal::Nanos stamp_ns, std::string_view parent_frame_id,
                           std::string_view child_frame_id, const Pose2& child_in_parent) noexcept {
  out.begin_object();
  write_time(out, "timestamp", stamp_ns);
  out.member("parent_frame_id", parent_frame_id);
  out.member("child_frame_id", child_frame_id);
  write_vector3(out, "translation", child_in_parent.x_m, child_in_parent.y_m, 0.0);
  write_yaw(out, "rotation", child_in_parent.theta_rad);
  out.end_object();
}

void write_poses_in_frame(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id,
                          std::span<const Pose2> poses) noexcept {
  out.begin_object();
  write_time(out, "timestamp", stamp_ns);
  out.member("frame_id", frame_id);
  out.key("poses").begin_array();
  for (const Pose2& p : poses) {
    out.begin_object();
    pose_members(out, p.x_m, p.y_m, 0.0, p.theta_rad);
    out.end_object();
  }
  out.end_array();
  out.end_object();
}

void write_compressed_image(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id,
                            std::span<const std::uint8_t> data, std::string_view format) noexcept {
  out.begin_object();
  write_time(out, "timestamp", stamp_ns);
  out.member("frame_id", frame_id);
  out.key("data").base64(data);
  out.member("format", format);
  out.end_object();
}

void write_scene_update(json::Writer& out, hal::Nanos stamp_ns, bool delete_all,
                        std::span<const Entity> entities) noexcept {
  out.begin_object();
  out.key("deletions").begin_array();
  if (delete_all) {
    out.begin_object();
    write_time(out, "timestamp", stamp_ns);
    out.member_uint32("type", 1);  // SceneEntityDeletionType ALL; the id is ignored
    out.member("id", "");
    out.end_object();
  }
  out.end_array();
  out.key("entities").begin_array();
  for (const Entity& e : entities) write_entity(out, stamp_ns, e);
  out.end_array();
  out.end_object();
}

}  // namespace sen3bot::view
