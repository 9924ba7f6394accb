// The advertised schemas. Each text describes exactly what the writers in foxglove.cpp (and
// the server, for the robot's own two) emit: every member they write is listed and required.
// The fragments are macros so that the whole text of each schema is one string literal.
#include "sen3bot/view/foxglove.hpp"

namespace sen3bot::view {
namespace {

#define S3_OBJ(title, props, req) \
  "{\"type\":\"object\",\"title\":\"" title "\",\"properties\":{" props "},\"required\":[" req "]}"
#define S3_NUM "{\"type\":\"number\"}"
#define S3_INT "{\"type\":\"integer\"}"
#define S3_UINT "{\"type\":\"integer\",\"minimum\":0}"
#define S3_STR "{\"type\":\"string\"}"
#define S3_BOOL "{\"type\":\"boolean\"}"
#define S3_BASE64 "{\"type\":\"string\",\"contentEncoding\":\"base64\"}"
#define S3_ARRAY(items) "{\"type\":\"array\",\"items\":" items "}"
#define S3_NSEC "{\"type\":\"integer\",\"minimum\":0,\"maximum\":999999999}"
#define S3_TIME S3_OBJ("time", "\"sec\":" S3_UINT ",\"nsec\":" S3_NSEC, "\"sec\",\"nsec\"")
#define S3_DURATION S3_OBJ("duration", "\"sec\":" S3_INT ",\"nsec\":" S3_NSEC, "\"sec\",\"nsec\"")
#define S3_XYZ "\"x\":" S3_NUM ",\"y\":" S3_NUM ",\"z\":" S3_NUM
#define S3_VECTOR2 S3_OBJ("foxglove.Vector2", "\"x\":" S3_NUM ",\"y\":" S3_NUM, "\"x\",\"y\"")
#define S3_VECTOR3 S3_OBJ("foxglove.Vector3", S3_XYZ, "\"x\",\"y\",\"z\"")
#define S3_POINT3 S3_OBJ("foxglove.Point3", S3_XYZ, "\"x\",\"y\",\"z\"")
#define S3_QUATERNION S3_OBJ("foxglove.Quaternion", S3_XYZ ",\"w\":" S3_NUM, "\"x\",\"y\",\"z\",\"w\"")
#define S3_POSE \
  S3_OBJ("foxglove.Pose", "\"position\":" S3_VECTOR3 ",\"orientation\":" S3_QUATERNION, "\"position\",\"orientation\"")
#define S3_COLOR                                                                                    \
  S3_OBJ("foxglove.Color", "\"r\":" S3_NUM ",\"g\":" S3_NUM ",\"b\":" S3_NUM ",\"a\":" S3_NUM, \
         "\"r\",\"g\",\"b\",\"a\"")
#define S3_ENUM(max) "{\"type\":\"integer\",\"minimum\":0,\"maximum\":" #max "}"
#define S3_XY_THETA "\"x\":" S3_NUM ",\"y\":" S3_NUM ",\"theta\":" S3_NUM

constexpr std::string_view kGrid = S3_OBJ(
    "foxglove.Grid",
    "\"timestamp\":" S3_TIME ",\"frame_id\":" S3_STR ",\"pose\":" S3_POSE ",\"column_count\":" S3_UINT
    ",\"cell_size\":" S3_VECTOR2 ",\"row_stride\":" S3_UINT ",\"cell_stride\":" S3_UINT
    ",\"fields\":" S3_ARRAY(S3_OBJ("foxglove.PackedElementField",
                                   "\"name\":" S3_STR ",\"offset\":" S3_UINT ",\"type\":" S3_ENUM(8),
                                   "\"name\",\"offset\",\"type\"")) ",\"data\":" S3_BASE64,
    "\"timestamp\",\"frame_id\",\"pose\",\"column_count\",\"cell_size\",\"row_stride\",\"cell_stride\",\"fields\","
    "\"data\"");

constexpr std::string_view kLaserScan = S3_OBJ(
    "foxglove.LaserScan",
    "\"timestamp\":" S3_TIME ",\"frame_id\":" S3_STR ",\"pose\":" S3_POSE ",\"start_angle\":" S3_NUM
    ",\"end_angle\":" S3_NUM ",\"ranges\":" S3_ARRAY(S3_NUM) ",\"intensities\":" S3_ARRAY(S3_NUM),
    "\"timestamp\",\"frame_id\",\"pose\",\"start_angle\",\"end_angle\",\"ranges\",\"intensities\"");

constexpr std::string_view kFrameTransform = S3_OBJ(
    "foxglove.FrameTransform",
    "\"timestamp\":" S3_TIME ",\"parent_frame_id\":" S3_STR ",\"child_frame_id\":" S3_STR
    ",\"translation\":" S3_VECTOR3 ",\"rotation\":" S3_QUATERNION,
    "\"timestamp\",\"parent_frame_id\",\"child_frame_id\",\"translation\",\"rotation\"");

constexpr std::string_view kPosesInFrame = S3_OBJ(
    "foxglove.PosesInFrame", "\"timestamp\":" S3_TIME ",\"frame_id\":" S3_STR ",\"poses\":" S3_ARRAY(S3_POSE),
    "\"timestamp\",\"frame_id\",\"poses\"");

constexpr std::string_view kCompressedImage = S3_OBJ(
    "foxglove.CompressedImage",
    "\"timestamp\":" S3_TIME ",\"frame_id\":" S3_STR ",\"data\":" S3_BASE64 ",\"format\":" S3_STR,
    "\"timestamp\",\"frame_id\",\"data\",\"format\"");

// Primitives the robot never sends are described as objects only: their arrays stay empty.
#define S3_ARROW                                                                                                    \
  S3_OBJ("foxglove.ArrowPrimitive",                                                                                 \
         "\"pose\":" S3_POSE ",\"shaft_length\":" S3_NUM ",\"shaft_diameter\":" S3_NUM ",\"head_length\":" S3_NUM \
         ",\"head_diameter\":" S3_NUM ",\"color\":" S3_COLOR,                                                       \
         "\"pose\",\"shaft_length\",\"shaft_diameter\",\"head_length\",\"head_diameter\",\"color\"")
#define S3_CYLINDER                                                                                               \
  S3_OBJ("foxglove.CylinderPrimitive",                                                                            \
         "\"pose\":" S3_POSE ",\"size\":" S3_VECTOR3 ",\"bottom_scale\":" S3_NUM ",\"top_scale\":" S3_NUM        \
         ",\"color\":" S3_COLOR,                                                                                  \
         "\"pose\",\"size\",\"bottom_scale\",\"top_scale\",\"color\"")
#define S3_LINE                                                                                                    \
  S3_OBJ("foxglove.LinePrimitive",                                                                                 \
         "\"type\":" S3_ENUM(2) ",\"pose\":" S3_POSE ",\"thickness\":" S3_NUM ",\"scale_invariant\":" S3_BOOL     \
         ",\"points\":" S3_ARRAY(S3_POINT3) ",\"color\":" S3_COLOR ",\"colors\":" S3_ARRAY(S3_COLOR)             \
         ",\"indices\":" S3_ARRAY(S3_UINT),                                                                        \
         "\"type\",\"pose\",\"thickness\",\"scale_invariant\",\"points\",\"color\",\"colors\",\"indices\"")
#define S3_TEXT                                                                                                      \
  S3_OBJ("foxglove.TextPrimitive",                                                                                   \
         "\"pose\":" S3_POSE ",\"billboard\":" S3_BOOL ",\"font_size\":" S3_NUM ",\"scale_invariant\":" S3_BOOL     \
         ",\"color\":" S3_COLOR ",\"text\":" S3_STR,                                                                 \
         "\"pose\",\"billboard\",\"font_size\",\"scale_invariant\",\"color\",\"text\"")
#define S3_KEY_VALUE S3_OBJ("foxglove.KeyValuePair", "\"key\":" S3_STR ",\"value\":" S3_STR, "\"key\",\"value\"")
#define S3_UNUSED "{\"type\":\"array\",\"items\":{\"type\":\"object\"}}"
#define S3_ENTITY                                                                                                     \
  S3_OBJ("foxglove.SceneEntity",                                                                                      \
         "\"timestamp\":" S3_TIME ",\"frame_id\":" S3_STR ",\"id\":" S3_STR ",\"lifetime\":" S3_DURATION              \
         ",\"frame_locked\":" S3_BOOL ",\"metadata\":" S3_ARRAY(S3_KEY_VALUE) ",\"arrows\":" S3_ARRAY(S3_ARROW)       \
         ",\"cubes\":" S3_UNUSED ",\"spheres\":" S3_UNUSED ",\"cylinders\":" S3_ARRAY(S3_CYLINDER)                    \
         ",\"lines\":" S3_ARRAY(S3_LINE) ",\"triangles\":" S3_UNUSED ",\"texts\":" S3_ARRAY(S3_TEXT)                  \
         ",\"models\":" S3_UNUSED,                                                                                    \
         "\"timestamp\",\"frame_id\",\"id\",\"lifetime\",\"frame_locked\",\"metadata\",\"arrows\",\"cubes\","         \
         "\"spheres\",\"cylinders\",\"lines\",\"triangles\",\"texts\",\"models\"")
#define S3_DELETION                                                                                             \
  S3_OBJ("foxglove.SceneEntityDeletion", "\"timestamp\":" S3_TIME ",\"type\":" S3_ENUM(1) ",\"id\":" S3_STR, \
         "\"timestamp\",\"type\",\"id\"")

constexpr std::string_view kSceneUpdate =
    S3_OBJ("foxglove.SceneUpdate", "\"deletions\":" S3_ARRAY(S3_DELETION) ",\"entities\":" S3_ARRAY(S3_ENTITY),
           "\"deletions\",\"entities\"");

#define S3_TASK                                                                                                     \
  S3_OBJ("sen3bot.TaskStats.Task",                                                                                 \
         "\"name\":" S3_STR ",\"thread\":" S3_STR ",\"period_us\":" S3_UINT ",\"budget_us\":" S3_UINT              \
         ",\"runs\":" S3_UINT ",\"overruns\":" S3_UINT ",\"slips\":" S3_UINT ",\"skips\":" S3_UINT                 \
         ",\"exec_mean_us\":" S3_NUM ",\"exec_max_us\":" S3_NUM ",\"cpu_mean_us\":" S3_NUM ",\"cpu_max_us\":" S3_NUM \
         ",\"jitter_p99_us\":" S3_NUM,                                                                              \
         "\"name\",\"thread\",\"period_us\",\"budget_us\",\"runs\",\"overruns\",\"slips\",\"skips\","              \
         "\"exec_mean_us\",\"exec_max_us\",\"cpu_mean_us\",\"cpu_max_us\",\"jitter_p99_us\"")
#define S3_VIEW_COUNTERS                                                                                           \
  S3_OBJ("sen3bot.TaskStats.View",                                                                                 \
         "\"clients\":" S3_UINT ",\"sent\":" S3_UINT ",\"dropped\":" S3_UINT ",\"rejected\":" S3_UINT,             \
         "\"clients\",\"sent\",\"dropped\",\"rejected\"")

constexpr std::string_view kTaskStats = S3_OBJ(
    "sen3bot.TaskStats",
    "\"timestamp\":" S3_TIME ",\"uptime_s\":" S3_NUM ",\"tasks\":" S3_ARRAY(S3_TASK) ",\"view\":" S3_VIEW_COUNTERS,
    "\"timestamp\",\"uptime_s\",\"tasks\",\"view\"");

constexpr std::string_view kMission = S3_OBJ(
    "sen3bot.Mission",
    "\"timestamp\":" S3_TIME ",\"state\":" S3_STR ",\"goals_reached\":" S3_UINT ",\"goals_total\":" S3_UINT
    ",\"goal\":{\"type\":[\"object\",\"null\"],\"properties\":{\"x\":" S3_NUM ",\"y\":" S3_NUM
    "},\"required\":[\"x\",\"y\"]},\"pose\":" S3_OBJ("sen3bot.Pose2", S3_XY_THETA, "\"x\",\"y\",\"theta\"")
    ",\"localized\":" S3_BOOL ",\"lost\":" S3_BOOL ",\"v\":" S3_NUM ",\"w\":" S3_NUM ",\"controller\":" S3_STR
    ",\"safety\":" S3_ARRAY(S3_STR) ",\"separation\":{\"type\":[\"object\",\"null\"],\"properties\":{\"cap\":" S3_NUM
    ",\"gap\":" S3_NUM ",\"approach\":" S3_NUM "},\"required\":[\"cap\",\"gap\",\"approach\"]}",
    "\"timestamp\",\"state\",\"goals_reached\",\"goals_total\",\"goal\",\"pose\",\"localized\",\"lost\",\"v\",\"w\","
    "\"controller\",\"safety\",\"separation\"");

#undef S3_OBJ
#undef S3_NUM
#undef S3_INT
#undef S3_UINT
#undef S3_STR
#undef S3_BOOL
#undef S3_BASE64
#undef S3_ARRAY
#undef S3_NSEC
#undef S3_TIME
#undef S3_DURATION
#undef S3_XYZ
#undef S3_VECTOR2
#undef S3_VECTOR3
#undef S3_POINT3
#undef S3_QUATERNION
#undef S3_POSE
#undef S3_COLOR
#undef S3_ENUM
#undef S3_XY_THETA
#undef S3_ARROW
#undef S3_CYLINDER
#undef S3_LINE
#undef S3_TEXT
#undef S3_KEY_VALUE
#undef S3_UNUSED
#undef S3_ENTITY
#undef S3_DELETION
#undef S3_TASK
#undef S3_VIEW_COUNTERS

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
  switch (schema) {
    case Schema::grid: return kGrid;
    case Schema::laser_scan: return kLaserScan;
    case Schema::frame_transform: return kFrameTransform;
    case Schema::poses_in_frame: return kPosesInFrame;
    case Schema::scene_update: return kSceneUpdate;
    case Schema::compressed_image: return kCompressedImage;
    case Schema::task_stats: return kTaskStats;
    case Schema::mission: return kMission;
  }
  return {};
}

}  // namespace sen3bot::view
