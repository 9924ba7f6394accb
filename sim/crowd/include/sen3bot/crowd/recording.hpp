#pragma once
// Recorded pedestrian trajectories (ETH/BIWI, UCY; data/pedestrians/README.md):
// text lines `frame_id person_id x_m y_m`, one per person per annotated frame, frames stepping
// by 10 per 0.4 s. Parsed once, off the real-time path (it allocates), into tracks: one
// contiguous walk of one person each, so a person who leaves the view and comes back is two
// tracks with nobody in between.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::crowd {

using msg::Point2D;

struct Sample {
  double time_s = 0.0;  // from the file's first frame
  Point2D position;
};

// One person's walk over consecutive annotated frames; times strictly increasing, never empty.
struct Track {
  std::int64_t person_id = 0;
  std::vector<Sample> samples;
};

struct Recording {
  std::string name;
  std::int64_t first_frame = 0;  // the smallest frame id of the file: time 0
  std::int64_t frame_step = 0;   // inferred annotation step in frame ids (0 with one frame only)
  std::vector<Track> tracks;     // ordered by start time, then person id
};

struct RecordingOptions {
  // The documented rate: one annotation step of 10 frame ids is 0.4 s.
  double seconds_per_frame = 0.4 / 10.0;
  // Faster than any walker or runner in a crowd scene: a jump implying more is an annotation
  // error (two people sharing an id), not a pedestrian.
  double max_speed_m_s = 5.0;
};

// Errors name the file and line: a line without 4 columns, a value that is not a finite
// number, a frame or person id that is not an integer (frames within +-1e9), a person moving faster than
// max_speed_m_s between consecutive annotations, a person's frames going backwards or repeating,
// no samples at all. Blank lines and lines starting with '#' are skipped. The annotation step
// is the most common difference between consecutive distinct frame ids; a person missing for
// more than one step is split into two tracks.
// The end of a long file name, leaving room for the rest of an error message.
[[nodiscard]] std::string_view name_tail(std::string_view name, std::size_t chars = 80) noexcept;

[[nodiscard]] Result<Recording> parse_recording(std::string_view text, std::string_view name,
                                                const RecordingOptions& options = {});
// Reads the file at `path` and parses it with the path as its name.
[[nodiscard]] Result<Recording> load_recording(const std::string& path, const RecordingOptions& options = {});

struct Extent {
  Point2D min;
  Point2D max;
};

// What a scene needs to be sized and printed.
struct Summary {
  std::size_t people = 0;   // distinct person ids
  std::size_t tracks = 0;   // a person with a gap counts once per walk
  std::size_t samples = 0;
  double start_s = 0.0;     // the time span covered by annotations
  double end_s = 0.0;
  Extent extent;            // of every annotated position
  std::size_t most_at_once = 0;    // the most people annotated in one frame
  double median_speed_m_s = 0.0;   // over consecutive annotation pairs within tracks (0 if none)
};

[[nodiscard]] Summary summarize(const Recording& recording);

struct FrameCount {
  double time_s = 0.0;
  std::size_t people = 0;
};

// The people annotated at each annotated time, in time order.
[[nodiscard]] std::vector<FrameCount> people_per_frame(const Recording& recording);

// The centre of the cell of a cell_m grid aligned on the origin that holds the most annotated
// positions (ties: the lowest cell by x, then y): where a robot's path should cross the crowd.
// Fails on an empty recording or a grid too fine for the extent.
[[nodiscard]] Result<Point2D> busiest_point(const Recording& recording, double cell_m = 1.0);

}  // namespace sen3bot::crowd
