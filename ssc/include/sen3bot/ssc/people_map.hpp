#pragma once
// The fleet-wide people map: every robot reports the people it sees (map frame, with its own
// local track ids); the centre keeps one global track per person. Association is gated
// nearest neighbour against each track's constant-velocity prediction, one-to-one within a
// report (two people one robot sees are two tracks), so a person two robots see at once is
// one track. A track is dynamic once its centre has moved more than a threshold (1 m in the
// thesis, §2.1.2) from where it was first detected; the label is kept for the track's life.
#include <cstdint>
#include <span>

#include "sen3bot/ssc/types.hpp"

namespace sen3bot::ssc {

struct PersonObservation {
  double x = 0;  // map frame, m
  double y = 0;
  double vx = 0;  // m/s
  double vy = 0;
  std::uint32_t local_track = 0;  // the reporting robot's own track id
};

struct PeopleReport {
  RobotId robot = kNone;
  Nanos stamp = 0;
  StaticVector<PersonObservation, kMaxPeoplePerReport> people;
};

struct PeopleMapConfig {
  double gate = 0.7;              // m: an observation farther than this from every prediction is a new person
  double dynamic_distance = 1.0;  // m from the first detected position
  Nanos timeout = hal::seconds(2);  // a track nobody has seen for this long is dropped
  double position_gain = 0.6;     // weight of a new observation against the prediction
  double merge_distance = 0.35;   // m: two tracks closer than this, no robot seeing both, are one person
  std::size_t max_tracks = kMaxTracks;  // at most kMaxTracks; lower only to exercise overflow
};

// One bit per robot id: every id the site can hold has a bit.
using RobotMask = std::uint64_t;
static_assert(kMaxRobots <= 64, "robot ids must fit the people map's 64-bit mask");

struct Track {
  std::uint32_t id = 0;  // global, never reused
  Point position;
  double vx = 0;
  double vy = 0;
  Point first_position;
  Nanos first_seen = 0;
  Nanos last_seen = 0;
  bool dynamic = false;
  RobotMask seen_by = 0;  // bit per robot id that saw it in its latest report
  std::uint32_t updates = 0;
};

// Who is inside one area.
struct AreaPeople {
  std::uint16_t count = 0;
  std::uint16_t dynamic = 0;
  [[nodiscard]] bool any() const noexcept { return count > 0; }
  [[nodiscard]] bool any_dynamic() const noexcept { return dynamic > 0; }
};

class PeopleMap {
 public:
  explicit PeopleMap(const PeopleMapConfig& config = {}) noexcept;

  // Folds one robot's report in. Observations beyond the capacity are counted, not kept.
  void update(const PeopleReport& report) noexcept;
  // Drops tracks not seen since now - timeout.
  void expire(Nanos now) noexcept;

  [[nodiscard]] std::span<const Track> tracks() const noexcept { return tracks_.as_span(); }
  [[nodiscard]] AreaPeople in_area(std::span<const Point> polygon) const noexcept;
  [[nodiscard]] std::uint64_t overflow() const noexcept { return overflow_; }  // people not tracked for lack of room
  [[nodiscard]] const PeopleMapConfig& config() const noexcept { return config_; }

 private:
  void merge_duplicates() noexcept;

  PeopleMapConfig config_;
  StaticVector<Track, kMaxTracks> tracks_;
  std::uint32_t next_id_ = 1;
  std::uint64_t overflow_ = 0;
};

}  // namespace sen3bot::ssc
