// `sen3bot map`: a map built from a recorded drive (a CARMEN log), written in the ROS
// map_server format the firmware's `navigation.map` reads, with the solved pose of every scan.
#include <chrono>
#include <cstdio>
#include <memory_resource>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.hpp"
#include "commands.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/slam/carmen.hpp"
#include "sen3bot/slam/mapper.hpp"

namespace sen3bot::firmware {
namespace {

constexpr const char* kMapUsage =
    "usage: sen3bot map --carmen FILE --out DIR/NAME.yaml [--resolution R] [--poses FILE]\n";

struct MapOptions {
  std::string carmen_path;
  std::string out_path;
  std::string poses_path;
  double resolution_m = 0.05;
};

// The scans a log holds, read once before mapping so the mapper's memory is sized to them.
Result<std::size_t> count_scans(const std::string& path) {
  Result<slam::CarmenReader> reader = slam::CarmenReader::open(path);
  if (!reader) return reader.error();
  std::vector<slam::LaserRecord> one(1);
  for (;;) {
    Result<bool> more = reader->next(one[0]);
    if (!more) return more.error();
    if (!*more) break;
  }
  return static_cast<std::size_t>(reader->counts().scans);
}

}  // namespace

int map_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  MapOptions o;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--carmen" && has_value) {
      o.carmen_path = argv[++i];
    } else if (arg == "--out" && has_value) {
      o.out_path = argv[++i];
    } else if (arg == "--poses" && has_value) {
      o.poses_path = argv[++i];
    } else if (arg == "--resolution" && has_value) {
      if (!parse_double(argv[++i], o.resolution_m) || !(o.resolution_m >= 0.01 && o.resolution_m <= 1.0)) {
        std::fprintf(err, "sen3bot map: --resolution: expected metres in [0.01, 1], got '%s'\n", argv[i]);
        return 2;
      }
    } else {
      std::fprintf(err, "sen3bot map: unknown or incomplete option '%s'\n%s", argv[i], kMapUsage);
      return 2;
    }
  }
  if (o.carmen_path.empty() || o.out_path.empty()) {
    std::fprintf(err, "sen3bot map: --carmen and --out are required\n%s", kMapUsage);
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  Result<std::size_t> scans = count_scans(o.carmen_path);
  if (!scans) {
    std::fprintf(err, "sen3bot map: %s\n", scans.error().c_str());
    return 1;
  }
  if (*scans == 0) {
    std::fprintf(err, "sen3bot map: %s holds no laser scan\n", o.carmen_path.c_str());
    return 1;
  }
  slam::MapperConfig config;
  config.resolution_m = o.resolution_m;
  slam::MapperCapacity capacity;
  capacity.scans = *scans;
  std::vector<std::byte> memory(slam::Mapper::bytes_for(config, capacity));
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  slam::Mapper mapper;
  if (Status s = mapper.init(arena, config, capacity); !s) {
    std::fprintf(err, "sen3bot map: %s\n", s.error().c_str());
    return 1;
  }
  Result<slam::CarmenReader> reader = slam::CarmenReader::open(o.carmen_path);
  if (!reader) {
    std::fprintf(err, "sen3bot map: %s\n", reader.error().c_str());
    return 1;
  }
  std::vector<slam::LaserRecord> record(1);
  std::size_t done = 0;
  std::size_t shown = 0;
  for (;;) {
    Result<bool> more = reader->next(record[0]);
    if (!more) {
      std::fprintf(err, "sen3bot map: %s\n", more.error().c_str());
      return 1;
    }
    if (!*more) break;
    if (Status s = mapper.add(record[0]); !s) {
      std::fprintf(err, "sen3bot map: scan %zu: %s\n", done, s.error().c_str());
      return 1;
    }
    ++done;
    if (done * 20 / *scans > shown) {
      shown = done * 20 / *scans;
      std::fprintf(err, "\rsen3bot map: %zu of %zu scans, %zu loop closures", done, *scans,
                   mapper.stats().loops_accepted);
      std::fflush(err);
    }
  }
  std::fputc('\n', err);
  if (Status s = mapper.finish(); !s) {
    std::fprintf(err, "sen3bot map: %s\n", s.error().c_str());
    return 1;
  }
  const double mapping_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Result<nav::OccupancyMap> map = mapper.render(o.resolution_m);
  if (!map) {
    std::fprintf(err, "sen3bot map: %s\n", map.error().c_str());
    return 1;
  }
  char comment[512];
  std::snprintf(comment, sizeof comment, "Sen3Bot map of %zu scans from %s", done, o.carmen_path.c_str());
  if (Status s = nav::save_map(*map, o.out_path, comment); !s) {
    std::fprintf(err, "sen3bot map: %s\n", s.error().c_str());
    return 1;
  }
  if (!o.poses_path.empty())
    if (Status s = slam::write_poses(mapper, o.poses_path); !s) {
      std::fprintf(err, "sen3bot map: %s\n", s.error().c_str());
      return 1;
    }
  const slam::MapperStats& st = mapper.stats();
  json::FileSink sink(out);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .member_uint64("scans", st.scans)
      .member_uint64("submaps", st.submaps)
      .key("loop_closures").begin_object()
      .member_uint64("searched", st.loop_searches)
      .member_uint64("accepted", st.loops_accepted)
      .member_uint64("rejected_ambiguous", st.loops_rejected_ambiguous)
      .end_object()
      .member_uint64("optimisations", st.optimisations)
      .member_fixed("optimisation_s", st.optimisation_s, 3)
      .member_fixed("matching_s", st.matching_s, 3)
      .member_fixed("loop_search_s", st.loop_search_s, 3)
      .member_fixed("total_s", mapping_s, 3)
      .key("map").begin_object()
      .member_uint32("width", static_cast<std::uint32_t>(map->width()))
      .member_uint32("height", static_cast<std::uint32_t>(map->height()))
      .member_fixed("resolution_m", map->resolution_m(), 3)
      .member("yaml", o.out_path)
      .end_object()
      .end_object();
  std::fputc('\n', out);
  return w.failed() ? 1 : 0;
}

}  // namespace sen3bot::firmware
