#include "sen3bot/crowd/recording.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <memory>
#include <unordered_map>
#include <utility>

#include "sen3bot/crowd/metrics.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {
namespace {

constexpr std::size_t kColumns = 4;  // frame_id person_id x_m y_m
constexpr const char* kColumnNames[kColumns] = {"frame id", "person id", "x", "y"};
// Every integer up to 2^53 is exact in a double, so an id read as a number is the id.
constexpr double kMaxExactInteger = 9007199254740992.0;
// Over a year of 25 fps video, and small enough that times keep sub-microsecond resolution.
constexpr double kMaxFrame = 1e9;
constexpr double kMaxMagnitude[2] = {kMaxFrame, kMaxExactInteger};  // frame id, person id
// The tail of a long path (the file's name) leaves room for the rest in Error's 256 chars.
constexpr std::size_t kNameChars = 80;
constexpr std::size_t kTokenChars = 24;

[[gnu::format(printf, 3, 4)]] Error line_error(std::string_view name, std::size_t line, const char* fmt, ...) {
  char what[Error::kMessageCapacity];
  std::va_list args;
  va_start(args, fmt);
  std::vsnprintf(what, sizeof what, fmt, args);
  va_end(args);
  const std::string_view file = name_tail(name, kNameChars);
  return Error::format(Errc::protocol, "%.*s:%zu: %s", static_cast<int>(file.size()), file.data(), line, what);
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Calls visit(first index, length) for each run of equal values in a sorted vector.
template <typename T, typename Visit>
void for_each_run(const std::vector<T>& sorted, Visit visit) {
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i + 1;
    while (j < sorted.size() && sorted[j] == sorted[i]) ++j;
    visit(i, j - i);
    i = j;
  }
}

struct Row {
  std::int64_t frame = 0;
  Point2D position;
};

// One person's annotations in file order (frames increasing), before they are cut into walks.
struct AnnotatedPerson {
  std::int64_t id = 0;
  std::vector<Row> rows;
};

class Parser {
 public:
  Parser(std::string_view name, const RecordingOptions& options) : name_(name), options_(options) {}

  Status add_line(std::string_view line, std::size_t line_number) {
    std::string_view tokens[kColumns];
    std::size_t count = 0;
    for (std::size_t i = 0; i < line.size();) {
      if (is_space(line[i])) {
        ++i;
        continue;
      }
      std::size_t end = i;
      while (end < line.size() && !is_space(line[end])) ++end;
      if (count == 0 && line[i] == '#') return {};
      if (count < kColumns) tokens[count] = line.substr(i, end - i);
      ++count;
      i = end;
    }
    if (count == 0) return {};
    if (count != kColumns) {
      return line_error(name_, line_number, "expected %zu columns (frame_id person_id x_m y_m), found %zu", kColumns,
                        count);
    }
    double values[kColumns];
    for (std::size_t c = 0; c < kColumns; ++c) {
      const std::string_view token = tokens[c];
      const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), values[c]);
      if (ec != std::errc{} || end != token.data() + token.size() || !std::isfinite(values[c])) {
        const std::string_view shown = token.substr(0, kTokenChars);
        return line_error(name_, line_number, "%s '%.*s' is not a finite number", kColumnNames[c],
                          static_cast<int>(shown.size()), shown.data());
      }
      if (c < 2 && (std::trunc(values[c]) != values[c] || std::fabs(values[c]) > kMaxMagnitude[c])) {
        const std::string_view shown = token.substr(0, kTokenChars);
        return line_error(name_, line_number, "%s '%.*s' is not an integer within +-%.0f", kColumnNames[c],
                          static_cast<int>(shown.size()), shown.data(), kMaxMagnitude[c]);
      }
    }
    return add_row(static_cast<std::int64_t>(values[1]), {static_cast<std::int64_t>(values[0]), {values[2], values[3]}},
                   line_number);
  }

  Result<Recording> finish() && {
    if (people_.empty()) {
      const std::string_view file = name_tail(name_, kNameChars);
      return Error::format(Errc::protocol, "%.*s: no samples", static_cast<int>(file.size()), file.data());
    }
    Recording recording;
    recording.name = std::string(name_);
    recording.first_frame = *std::min_element(frames_.begin(), frames_.end());
    recording.frame_step = most_common_step();
    for (const AnnotatedPerson& person : people_) split_into_tracks(person, recording);
    std::sort(recording.tracks.begin(), recording.tracks.end(), [](const Track& a, const Track& b) {
      const double ta = a.samples.front().time_s;
      const double tb = b.samples.front().time_s;
      return ta != tb ? ta < tb : a.person_id < b.person_id;
    });
    return recording;
  }

 private:
  Status add_row(std::int64_t id, Row row, std::size_t line_number) {
    frames_.push_back(row.frame);
    const auto [it, inserted] = index_.try_emplace(id, people_.size());
    if (inserted) {
      people_.push_back({id, {row}});
      return {};
    }
    AnnotatedPerson& person = people_[it->second];
    const Row& last = person.rows.back();
    if (row.frame < last.frame) {
      return line_error(name_, line_number, "person %lld at frame %lld after frame %lld (frames go backwards)",
                        static_cast<long long>(id), static_cast<long long>(row.frame),
                        static_cast<long long>(last.frame));
    }
    if (row.frame == last.frame) {
      return line_error(name_, line_number, "person %lld twice in frame %lld", static_cast<long long>(id),
                        static_cast<long long>(row.frame));
    }
    const double dt_s = static_cast<double>(row.frame - last.frame) * options_.seconds_per_frame;
    const double distance_m = msg::norm(row.position - last.position);
    if (!(distance_m <= options_.max_speed_m_s * dt_s)) {
      return line_error(name_, line_number, "person %lld jumps %.2f m in %.2f s (over %.1f m/s)",
                        static_cast<long long>(id), distance_m, dt_s, options_.max_speed_m_s);
    }
    person.rows.push_back(row);
    return {};
  }

  // The most common difference between consecutive distinct frame ids (the smallest on a tie).
  std::int64_t most_common_step() {
    std::sort(frames_.begin(), frames_.end());
    frames_.erase(std::unique(frames_.begin(), frames_.end()), frames_.end());
    std::vector<std::int64_t> steps;
    steps.reserve(frames_.size());
    for (std::size_t i = 1; i < frames_.size(); ++i) steps.push_back(frames_[i] - frames_[i - 1]);
    std::sort(steps.begin(), steps.end());
    std::int64_t best = 0;
    std::size_t best_count = 0;
    for_each_run(steps, [&](std::size_t first, std::size_t count) {
      if (count > best_count) {
        best = steps[first];
        best_count = count;
      }
    });
    return best;
  }

  // A person missing for more than one annotation step left the view: a new walk begins.
  void split_into_tracks(const AnnotatedPerson& person, Recording& recording) const {
    const Row* previous = nullptr;
    for (const Row& row : person.rows) {
      if (previous == nullptr || row.frame - previous->frame > recording.frame_step) {
        recording.tracks.push_back({person.id, {}});
      }
      const double time_s = static_cast<double>(row.frame - recording.first_frame) * options_.seconds_per_frame;
      recording.tracks.back().samples.push_back({time_s, row.position});
      previous = &row;
    }
  }

  std::string_view name_;
  RecordingOptions options_;
  std::vector<AnnotatedPerson> people_;  // in order of first appearance
  std::unordered_map<std::int64_t, std::size_t> index_;  // person id -> people_ index
  std::vector<std::int64_t> frames_;  // every annotation's frame
};

}  // namespace

std::string_view name_tail(std::string_view name, std::size_t chars) noexcept {
  return name.size() <= chars ? name : name.substr(name.size() - chars);
}

Result<Recording> parse_recording(std::string_view text, std::string_view name, const RecordingOptions& options) {
  if (!(options.seconds_per_frame > 0.0 && std::isfinite(options.seconds_per_frame)) ||
      !(options.max_speed_m_s > 0.0 && std::isfinite(options.max_speed_m_s))) {
    return Error::format(Errc::invalid_argument,
                         "recording options: seconds_per_frame %g and max_speed_m_s %g must be positive",
                         options.seconds_per_frame, options.max_speed_m_s);
  }
  Parser parser(name, options);
  std::size_t line_number = 0;
  while (!text.empty()) {
    ++line_number;
    const std::size_t end = text.find('\n');
    const Status added = parser.add_line(text.substr(0, end), line_number);
    if (!added) return added.error();
    text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
  }
  return std::move(parser).finish();
}

Result<Recording> load_recording(const std::string& path, const RecordingOptions& options) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return Error::from_errno(errno == ENOENT ? Errc::not_found : Errc::io, path, errno);
  std::string text;
  char chunk[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(chunk, 1, sizeof chunk, file.get())) > 0) text.append(chunk, n);
  if (std::ferror(file.get())) return Error::from_errno(Errc::io, path, errno);
  return parse_recording(text, path, options);
}

Summary summarize(const Recording& recording) {
  Summary summary;
  std::vector<std::int64_t> ids;
  std::vector<double> speeds_m_s;
  for (const Track& track : recording.tracks) {
    ids.push_back(track.person_id);
    for (std::size_t i = 0; i < track.samples.size(); ++i) {
      const Sample& s = track.samples[i];
      if (summary.samples++ == 0) {
        summary.start_s = summary.end_s = s.time_s;
        summary.extent = {s.position, s.position};
      }
      summary.start_s = std::min(summary.start_s, s.time_s);
      summary.end_s = std::max(summary.end_s, s.time_s);
      Extent& e = summary.extent;
      e.min = {std::min(e.min.x_m, s.position.x_m), std::min(e.min.y_m, s.position.y_m)};
      e.max = {std::max(e.max.x_m, s.position.x_m), std::max(e.max.y_m, s.position.y_m)};
      if (i > 0) {
        const Sample& p = track.samples[i - 1];
        speeds_m_s.push_back(msg::norm(s.position - p.position) / (s.time_s - p.time_s));
      }
    }
  }
  std::sort(ids.begin(), ids.end());
  summary.people = static_cast<std::size_t>(std::unique(ids.begin(), ids.end()) - ids.begin());
  summary.tracks = recording.tracks.size();
  for (const FrameCount& frame : people_per_frame(recording)) {
    summary.most_at_once = std::max(summary.most_at_once, frame.people);
  }
  summary.median_speed_m_s = speeds_m_s.empty() ? 0.0 : quartiles(speeds_m_s).median;
  return summary;
}

std::vector<FrameCount> people_per_frame(const Recording& recording) {
  std::vector<double> times_s;
  for (const Track& track : recording.tracks) {
    for (const Sample& s : track.samples) times_s.push_back(s.time_s);
  }
  std::sort(times_s.begin(), times_s.end());
  // A person is annotated at most once per frame and their walks never overlap, so the
  // annotations at a time are the people in view then.
  std::vector<FrameCount> counts;
  for_each_run(times_s, [&](std::size_t first, std::size_t count) { counts.push_back({times_s[first], count}); });
  return counts;
}

Result<Point2D> busiest_point(const Recording& recording, double cell_m) {
  if (!(cell_m > 0.0 && std::isfinite(cell_m))) {
    return Error::format(Errc::invalid_argument, "busiest_point: cell size %g m must be positive", cell_m);
  }
  std::vector<std::pair<std::int64_t, std::int64_t>> cells;
  for (const Track& track : recording.tracks) {
    for (const Sample& s : track.samples) {
      const double col = std::floor(s.position.x_m / cell_m);
      const double row = std::floor(s.position.y_m / cell_m);
      if (!(std::fabs(col) <= kMaxExactInteger && std::fabs(row) <= kMaxExactInteger)) {
        return Error::format(Errc::invalid_argument, "busiest_point: %g m cells are too fine for (%g, %g) m", cell_m,
                             s.position.x_m, s.position.y_m);
      }
      cells.emplace_back(static_cast<std::int64_t>(col), static_cast<std::int64_t>(row));
    }
  }
  if (cells.empty()) {
    return Error::format(Errc::invalid_argument, "busiest_point: %s has no samples", recording.name.c_str());
  }
  std::sort(cells.begin(), cells.end());
  std::size_t best = 0;
  std::size_t best_count = 0;
  for_each_run(cells, [&](std::size_t first, std::size_t count) {
    if (count > best_count) {
      best = first;
      best_count = count;
    }
  });
  const auto [col, row] = cells[best];
  return Point2D{(static_cast<double>(col) + 0.5) * cell_m, (static_cast<double>(row) + 0.5) * cell_m};
}

}  // namespace sen3bot::crowd
