// The advertised schemas. Each describes exactly what the writers in foxglove.cpp (and the
// server, for the robot's own two) emit: every member they write is listed and required. They
// are written once, with the JSON writer, into static buffers on the first call.
#include <array>
#include <initializer_list>

#include "sen3bot/view/foxglove.hpp"

namespace sen3bot::view {
namespace {

using json::Writer;
using Names = std::initializer_list<std::string_view>;

// {"type":"object","title":TITLE,"properties":{...},"required":[...]}: `properties` writes the
// members, `required` names them.
template <typename Properties>
void object(Writer& w, std::string_view title, const Properties& properties, Names required) {
  w.begin_object().member("type", "object").member("title", title).key("properties").begin_object();
  properties(w);
  w.end_object().key("required").begin_array();
  for (const std::string_view name : required) w.string(name);
  w.end_array().end_object();
}

void typed(Writer& w, std::string_view type) { w.begin_object().member("type", type).end_object(); }
void number(Writer& w) { typed(w, "number"); }
void integer(Writer& w) { typed(w, "integer"); }
void string(Writer& w) { typed(w, "string"); }
void boolean(Writer& w) { typed(w, "boolean"); }
void uint(Writer& w) { w.begin_object().member("type", "integer").member_uint32("minimum", 0).end_object(); }
void enumeration(Writer& w, std::uint32_t max) {
  w.begin_object().member("type", "integer").member_uint32("minimum", 0).member_uint32("maximum", max).end_object();
}
void nsec(Writer& w) { enumeration(w, 999999999); }
void base64(Writer& w) { w.begin_object().member("type", "string").member("contentEncoding", "base64").end_object(); }
template <typename Items>
void array(Writer& w, const Items& items) {
  w.begin_object().member("type", "array").key("items");
  items(w);
  w.end_object();
}
// An array whose items the robot never sends: described as objects only.
void unused(Writer& w) {
  array(w, [](Writer& a) { typed(a, "object"); });
}

// One member: its name, then what `write` writes.
template <typename Write>
void property(Writer& w, std::string_view name, const Write& write) {
  w.key(name);
  write(w);
}

void time_object(Writer& w, std::string_view title, void (*seconds)(Writer&)) {
  object(w, title, [&](Writer& o) { property(o, "sec", seconds); property(o, "nsec", nsec); }, {"sec", "nsec"});
}
void time(Writer& w) { time_object(w, "time", uint); }
void duration(Writer& w) { time_object(w, "duration", integer); }
void xyz(Writer& w) { property(w, "x", number); property(w, "y", number); property(w, "z", number); }
void vector2(Writer& w) {
  object(w, "foxglove.Vector2", [](Writer& o) { property(o, "x", number); property(o, "y", number); }, {"x", "y"});
}
void vector3(Writer& w) { object(w, "foxglove.Vector3", xyz, {"x", "y", "z"}); }
void point3(Writer& w) { object(w, "foxglove.Point3", xyz, {"x", "y", "z"}); }
void quaternion(Writer& w) {
  object(w, "foxglove.Quaternion", [](Writer& o) { xyz(o); property(o, "w", number); }, {"x", "y", "z", "w"});
}
void pose(Writer& w) {
  object(w, "foxglove.Pose", [](Writer& o) { property(o, "position", vector3); property(o, "orientation", quaternion); },
         {"position", "orientation"});
}
void color(Writer& w) {
  object(w, "foxglove.Color",
         [](Writer& o) { property(o, "r", number); property(o, "g", number); property(o, "b", number); property(o, "a", number); },
         {"r", "g", "b", "a"});
}
// An object or null: {"type":["object","null"],"properties":{...},"required":[...]}.
template <typename Properties>
void object_or_null(Writer& w, const Properties& properties, Names required) {
  w.begin_object().key("type").begin_array().string("object").string("null").end_array().key("properties").begin_object();
  properties(w);
  w.end_object().key("required").begin_array();
  for (const std::string_view name : required) w.string(name);
  w.end_array().end_object();
}

void grid(Writer& w) {
  object(w, "foxglove.Grid", [](Writer& o) {
    property(o, "timestamp", time); property(o, "frame_id", string); property(o, "pose", pose);
    property(o, "column_count", uint); property(o, "cell_size", vector2); property(o, "row_stride", uint);
    property(o, "cell_stride", uint);
    property(o, "fields", [](Writer& a) {
      array(a, [](Writer& f) {
        object(f, "foxglove.PackedElementField", [](Writer& e) {
          property(e, "name", string); property(e, "offset", uint); property(e, "type", [](Writer& t) { enumeration(t, 8); });
        }, {"name", "offset", "type"});
      });
    });
    property(o, "data", base64);
  }, {"timestamp", "frame_id", "pose", "column_count", "cell_size", "row_stride", "cell_stride", "fields", "data"});
}

void laser_scan(Writer& w) {
  object(w, "foxglove.LaserScan", [](Writer& o) {
    property(o, "timestamp", time); property(o, "frame_id", string); property(o, "pose", pose);
    property(o, "start_angle", number); property(o, "end_angle", number);
    property(o, "ranges", [](Writer& a) { array(a, number); });
    property(o, "intensities", [](Writer& a) { array(a, number); });
  }, {"timestamp", "frame_id", "pose", "start_angle", "end_angle", "ranges", "intensities"});
}

void frame_transform(Writer& w) {
  object(w, "foxglove.FrameTransform", [](Writer& o) {
    property(o, "timestamp", time); property(o, "parent_frame_id", string); property(o, "child_frame_id", string);
    property(o, "translation", vector3); property(o, "rotation", quaternion);
  }, {"timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"});
}

void poses_in_frame(Writer& w) {
  object(w, "foxglove.PosesInFrame", [](Writer& o) {
    property(o, "timestamp", time); property(o, "frame_id", string);
    property(o, "poses", [](Writer& a) { array(a, pose); });
  }, {"timestamp", "frame_id", "poses"});
}

void compressed_image(Writer& w) {
  object(w, "foxglove.CompressedImage", [](Writer& o) {
    property(o, "timestamp", time); property(o, "frame_id", string); property(o, "data", base64);
    property(o, "format", string);
  }, {"timestamp", "frame_id", "data", "format"});
}

void arrow(Writer& w) {
  object(w, "foxglove.ArrowPrimitive", [](Writer& o) {
    property(o, "pose", pose); property(o, "shaft_length", number); property(o, "shaft_diameter", number);
    property(o, "head_length", number); property(o, "head_diameter", number); property(o, "color", color);
  }, {"pose", "shaft_length", "shaft_diameter", "head_length", "head_diameter", "color"});
}

void cylinder(Writer& w) {
  object(w, "foxglove.CylinderPrimitive", [](Writer& o) {
    property(o, "pose", pose); property(o, "size", vector3); property(o, "bottom_scale", number);
    property(o, "top_scale", number); property(o, "color", color);
  }, {"pose", "size", "bottom_scale", "top_scale", "color"});
}

void line(Writer& w) {
  object(w, "foxglove.LinePrimitive", [](Writer& o) {
    property(o, "type", [](Writer& t) { enumeration(t, 2); });
    property(o, "pose", pose); property(o, "thickness", number); property(o, "scale_invariant", boolean);
    property(o, "points", [](Writer& a) { array(a, point3); });
    property(o, "color", color);
    property(o, "colors", [](Writer& a) { array(a, color); });
    property(o, "indices", [](Writer& a) { array(a, uint); });
  }, {"type", "pose", "thickness", "scale_invariant", "points", "color", "colors", "indices"});
}

void text(Writer& w) {
  object(w, "foxglove.TextPrimitive", [](Writer& o) {
    property(o, "pose", pose); property(o, "billboard", boolean); property(o, "font_size", number);
    property(o, "scale_invariant", boolean); property(o, "color", color); property(o, "text", string);
  }, {"pose", "billboard", "font_size", "scale_invariant", "color", "text"});
}

void key_value(Writer& w) {
  object(w, "foxglove.KeyValuePair", [](Writer& o) { property(o, "key", string); property(o, "value", string); },
         {"key", "value"});
}

void entity(Writer& w) {
  object(w, "foxglove.SceneEntity", [](Writer& o) {
    property(o, "timestamp", time); property(o, "frame_id", string); property(o, "id", string);
    property(o, "lifetime", duration); property(o, "frame_locked", boolean);
    property(o, "metadata", [](Writer& a) { array(a, key_value); });
    property(o, "arrows", [](Writer& a) { array(a, arrow); });
    property(o, "cubes", unused); property(o, "spheres", unused);
    property(o, "cylinders", [](Writer& a) { array(a, cylinder); });
    property(o, "lines", [](Writer& a) { array(a, line); });
    property(o, "triangles", unused);
    property(o, "texts", [](Writer& a) { array(a, text); });
    property(o, "models", unused);
  }, {"timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata", "arrows", "cubes", "spheres", "cylinders",
      "lines", "triangles", "texts", "models"});
}

void deletion(Writer& w) {
  object(w, "foxglove.SceneEntityDeletion", [](Writer& o) {
    property(o, "timestamp", time); property(o, "type", [](Writer& t) { enumeration(t, 1); }); property(o, "id", string);
  }, {"timestamp", "type", "id"});
}

void scene_update(Writer& w) {
  object(w, "foxglove.SceneUpdate", [](Writer& o) {
    property(o, "deletions", [](Writer& a) { array(a, deletion); });
    property(o, "entities", [](Writer& a) { array(a, entity); });
  }, {"deletions", "entities"});
}

void task(Writer& w) {
  object(w, "sen3bot.TaskStats.Task", [](Writer& o) {
    property(o, "name", string); property(o, "thread", string); property(o, "period_us", uint);
    property(o, "budget_us", uint); property(o, "runs", uint); property(o, "overruns", uint);
    property(o, "slips", uint); property(o, "skips", uint); property(o, "exec_mean_us", number);
    property(o, "exec_max_us", number); property(o, "cpu_mean_us", number); property(o, "cpu_max_us", number);
    property(o, "jitter_p99_us", number);
  }, {"name", "thread", "period_us", "budget_us", "runs", "overruns", "slips", "skips", "exec_mean_us", "exec_max_us",
      "cpu_mean_us", "cpu_max_us", "jitter_p99_us"});
}

void view_counters(Writer& w) {
  object(w, "sen3bot.TaskStats.View", [](Writer& o) {
    property(o, "clients", uint); property(o, "sent", uint); property(o, "dropped", uint); property(o, "rejected", uint);
  }, {"clients", "sent", "dropped", "rejected"});
}

void task_stats(Writer& w) {
  object(w, "sen3bot.TaskStats", [](Writer& o) {
    property(o, "timestamp", time); property(o, "uptime_s", number);
    property(o, "tasks", [](Writer& a) { array(a, task); });
    property(o, "view", view_counters);
  }, {"timestamp", "uptime_s", "tasks", "view"});
}

void mission(Writer& w) {
  object(w, "sen3bot.Mission", [](Writer& o) {
    property(o, "timestamp", time); property(o, "state", string); property(o, "goals_reached", uint);
    property(o, "goals_total", uint);
    property(o, "goal", [](Writer& g) {
      object_or_null(g, [](Writer& p) { property(p, "x", number); property(p, "y", number); }, {"x", "y"});
    });
    property(o, "pose", [](Writer& p) {
      object(p, "sen3bot.Pose2", [](Writer& q) { property(q, "x", number); property(q, "y", number); property(q, "theta", number); },
             {"x", "y", "theta"});
    });
    property(o, "localized", boolean); property(o, "lost", boolean); property(o, "v", number); property(o, "w", number);
    property(o, "controller", string);
    property(o, "safety", [](Writer& a) { array(a, string); });
    property(o, "separation", [](Writer& s) {
      object_or_null(s, [](Writer& p) { property(p, "cap", number); property(p, "gap", number); property(p, "approach", number); },
                     {"cap", "gap", "approach"});
    });
  }, {"timestamp", "state", "goals_reached", "goals_total", "goal", "pose", "localized", "lost", "v", "w", "controller",
      "safety", "separation"});
}

// Every schema's text, written once.
struct Schemas {
  std::array<char, 16384> buffer{};
  std::array<std::string_view, kSchemaCount> text{};

  Schemas() noexcept {
    void (*const writers[kSchemaCount])(Writer&) = {grid,         laser_scan,       frame_transform, poses_in_frame,
                                                    scene_update, compressed_image, task_stats,      mission};
    std::size_t used = 0;
    for (std::size_t i = 0; i < kSchemaCount; ++i) {
      Writer w(std::span<char>(buffer).subspan(used));
      writers[i](w);
      // The buffer is sized for all of them (a test checks each parses); a failure leaves "".
      if (auto done = w.finish()) {
        text[i] = *done;
        used += done->size();
      }
    }
  }
};

}  // namespace

std::string_view schema_name(Schema schema) noexcept {
  switch (schema) {
    case Schema::grid: return "foxglove.Grid";
    case Schema::laser_scan: return "foxglove.LaserScan";
    case Schema::frame_transform: return "foxglove.FrameTransform";
    case Schema::poses_in_frame: return "foxglove.PosesInFrame";
    case Schema::scene_update: return "foxglove.SceneUpdate";
    case Schema::compressed_image: return "foxglove.CompressedImage";
    case Schema::task_stats: return "sen3bot.TaskStats";
    case Schema::mission: return "sen3bot.Mission";
  }
  return {};
}

std::string_view json_schema(Schema schema) noexcept {
  static const Schemas schemas;
  const auto i = static_cast<std::size_t>(schema);
  return i < kSchemaCount ? schemas.text[i] : std::string_view();
}

}  // namespace sen3bot::view
