#pragma once
// The Foxglove well-known schemas, written as JSON (the `json` message encoding of the
// foxglove.websocket.v1 subprotocol) into a caller's buffer: nothing is allocated. Each
// writer emits one complete message, every field its schema names included (empty arrays for
// primitives an entity does not use), so the Foxglove app draws it without plugins. Bytes
// fields (grid cells, JPEG data) are base64, times are {sec, nsec}.
//
// Frames: "map" (the occupancy map's), "odom", "base_link" (the axle's centre), "laser".
// Angles are radians, positions metres, z = 0 (the robot is planar).
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/geometry/geometry.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::view {

namespace json = sen3bot::json;

// The schemas this server advertises: the well-known Foxglove ones and two of the robot's own
// (plain JSON objects, described by their JSON Schema in docs/view.md).
enum class Schema : std::uint8_t {
  grid,              // foxglove.Grid
  laser_scan,        // foxglove.LaserScan
  frame_transform,   // foxglove.FrameTransform
  poses_in_frame,    // foxglove.PosesInFrame
  scene_update,      // foxglove.SceneUpdate
  compressed_image,  // foxglove.CompressedImage
  task_stats,        // sen3bot.TaskStats
  mission,           // sen3bot.Mission
};
inline constexpr std::size_t kSchemaCount = 8;
std::string_view schema_name(Schema schema) noexcept;  // "foxglove.Grid", ...
// The schema as JSON Schema text (draft 2020-12 keywords only where needed), the `schema`
// field of an advertised channel. Written once, on the first call, into static memory (nothing
// is allocated); valid JSON.
std::string_view json_schema(Schema schema) noexcept;

// A time or duration as the schemas' {sec, nsec}, under `name`: negative clamps to 0, beyond the
// u32 seconds to the last one. For the robot's own JSON messages too.
void write_time(json::Writer& out, std::string_view name, hal::Nanos ns) noexcept;

using Point2 = geometry::Point2D;
using Pose2 = geometry::Pose2D;
struct Color {
  double r = 0.0, g = 0.0, b = 0.0, a = 1.0;  // 0..1
};

// A grid of one uint8 field per cell, row-major from the cell at the origin (row 0 is the
// lowest y), its origin the corner of cell (0, 0) in frame_id, unrotated.
struct GridView {
  std::span<const std::uint8_t> cells;  // columns * rows
  std::uint32_t columns = 0;
  std::uint32_t rows = 0;
  double resolution_m = 0.05;
  Point2 origin;
  std::string_view field = "cost";  // the field's name: "occupancy" (map), "cost" (costmaps)
};
void write_grid(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id, const GridView& grid) noexcept;

// Readings at start + i * increment; a reading outside [range_min, range_max) is "no return"
// and is written as 0.
void write_laser_scan(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id, std::span<const float> ranges_m,
                      double start_angle_rad, double increment_rad, double range_min_m, double range_max_m) noexcept;

void write_frame_transform(json::Writer& out, hal::Nanos stamp_ns, std::string_view parent_frame_id,
                           std::string_view child_frame_id, const Pose2& child_in_parent) noexcept;

void write_poses_in_frame(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id,
                          std::span<const Pose2> poses) noexcept;

void write_compressed_image(json::Writer& out, hal::Nanos stamp_ns, std::string_view frame_id,
                            std::span<const std::uint8_t> data, std::string_view format) noexcept;

// foxglove.SceneUpdate: entities of lines, flat cylinders (discs, people), arrows (velocities)
// and texts (labels), all in the plane.
enum class LineType : std::uint8_t { strip = 0, loop = 1, list = 2 };
struct Line {
  LineType type = LineType::strip;
  std::span<const Point2> points;
  double thickness_m = 0.03;
  Color color;
};
struct Cylinder {
  Point2 centre;
  double diameter_m = 0.5;
  double height_m = 1.7;
  Color color;
};
struct Arrow {
  Point2 from;
  double heading_rad = 0.0;
  double length_m = 0.5;  // > 0
  Color color;
};
struct Text {
  Point2 at;
  std::string_view text;
  double font_size = 12.0;  // pixels (scale invariant)
  Color color;
};
struct Entity {
  std::string_view id;
  std::string_view frame_id = "map";
  hal::Nanos lifetime_ns = 0;  // 0: until replaced or deleted
  std::span<const Line> lines;
  std::span<const Cylinder> cylinders;
  std::span<const Arrow> arrows;
  std::span<const Text> texts;
};
// delete_all: the update first deletes every entity of the channel (type ALL), so entities
// that are gone (a person who left) vanish.
void write_scene_update(json::Writer& out, hal::Nanos stamp_ns, bool delete_all, std::span<const Entity> entities) noexcept;

}  // namespace sen3bot::view
