#include "sen3bot/sim/referee.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sen3bot::sim {

namespace {
constexpr double kTrackSpacingM = 0.05;

// Appends p when it is at least kTrackSpacingM from the last point kept and there is room.
template <std::size_t N>
void keep_spaced(std::array<msg::Point2D, N>& points, std::size_t& count, double x_m, double y_m) noexcept {
  if (count == N) return;
  if (count == 0 || !std::isfinite(points[count - 1].x_m) || std::hypot(x_m - points[count - 1].x_m, y_m - points[count - 1].y_m) >= kTrackSpacingM)
    points[count++] = {x_m, y_m};
}
}  // namespace

void Referee::observe(const GroundTruth& truth) noexcept {
  const double t_s = static_cast<double>(truth.stamp_ns) / 1e9;
  if (truth.contacts > report_.contacts && contact_count_ < kMaxContacts)
    contacts_[contact_count_++] = {t_s, truth.pose, truth.moving_contacts > report_.moving_contacts, truth.contact_person};
  if (pose_count_ < kMaxPoses && (pose_count_ == 0 || t_s - poses_[pose_count_ - 1].t_s >= kPoseIntervalS - 1e-9)) {
    poses_[pose_count_++] = {t_s, truth.pose, false};
    for (std::size_t k = 0; k < truth.people_count && person_path_count_ < kMaxPersonPath; ++k)
      person_path_[person_path_count_++] = {t_s, truth.people_movers[k], truth.people[k]};
  }
  report_.contacts = truth.contacts;
  report_.moving_contacts = truth.moving_contacts;
  report_.min_clearance_m = std::min(report_.min_clearance_m, truth.clearance_m);
  report_.min_person_distance_m = std::min(report_.min_person_distance_m, truth.nearest_person_m);
  const msg::Pose2D& p = truth.pose;
  // Being carried off is not driving.
  const bool carried = truth.kidnapped_ns >= 0 && truth.kidnapped_ns == truth.stamp_ns;
  if (have_last_ && !carried) report_.true_path_length_m += std::hypot(p.x_m - last_.x_m, p.y_m - last_.y_m);
  last_ = p;
  have_last_ = true;
  if (carried && track_count_ > 0 && track_count_ < kMaxTrack)
    track_[track_count_++] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  keep_spaced(track_, track_count_, p.x_m, p.y_m);
  // Each estimate once, against the truth of the first step after it was published (at most
  // one world step, 5 ms, later): comparing an older estimate with a newer truth would count the
  // motion in between as error.
  judge_people(truth);
  tasks::Sample<msg::PoseEstimate> estimate;
  if (estimate_ != nullptr && estimate_->published() != estimate_sequence_ && estimate_->read(estimate)) {
    estimate_sequence_ = estimate.sequence;
    const double error_m = std::hypot(estimate.value.pose.x_m - p.x_m, estimate.value.pose.y_m - p.y_m);
    if (estimate.value.valid)
      keep_spaced(estimate_track_, estimate_track_count_, estimate.value.pose.x_m, estimate.value.pose.y_m);
    if (estimate.value.valid && std::abs(truth.speed_m_s) > kRobotMovingSpeedM_s)
      report_.localization_error_max_m = std::max(report_.localization_error_max_m, error_m);
    // Relocalisation: judged on every estimate after the kidnapping, moving or not.
    if (truth.kidnapped_ns >= 0 && estimate.value.stamp_ns >= truth.kidnapped_ns) {
      const double error_rad = std::abs(msg::normalize_angle(estimate.value.pose.theta_rad - p.theta_rad));
      const bool close = estimate.value.valid && error_m <= kRelocalizedM && error_rad <= kRelocalizedRad;
      if (!close) {
        close_since_ns_ = -1;
        report_.relocalization_s = -1;
      } else if (close_since_ns_ < 0) {
        close_since_ns_ = truth.stamp_ns;
        report_.relocalization_s = static_cast<double>(truth.stamp_ns - truth.kidnapped_ns) * 1e-9;
      }
    }
  }
}

void Referee::judge_people(const GroundTruth& truth) noexcept {
  tasks::Sample<msg::People> people;
  if (people_ == nullptr || people_->published() == people_sequence_ || !people_->read(people)) return;
  people_sequence_ = people.sequence;
  const msg::Pose2D& robot = truth.pose;
  for (std::size_t i = 0; i < std::min<std::size_t>(people.value.count, msg::People::kMax); ++i) {
    const msg::TrackedPerson& p = people.value.items[i];
    // Judged while observed: a person out of both sensors' view is carried on by a guess.
    if (static_cast<double>(people.value.stamp_ns - p.last_seen_ns) > kPersonFreshS * 1e9) continue;
    double best = std::numeric_limits<double>::infinity();
    std::size_t nearest = 0;
    for (std::size_t k = 0; k < truth.people_count; ++k) {
      const double d = std::hypot(p.x_m - truth.people[k].x_m, p.y_m - truth.people[k].y_m);
      if (d < best) {
        best = d;
        nearest = k;
      }
    }
    if (!(best <= kPersonMatchM)) {
      ++report_.false_people;
      continue;
    }
    const double range = std::hypot(truth.people[nearest].x_m - robot.x_m, truth.people[nearest].y_m - robot.y_m);
    if (range < kPersonRangeMinM || range > kPersonRangeMaxM) continue;
    ++report_.people_judged;
    if (person_error_count_ < kMaxPersonErrors) person_errors_[person_error_count_++] = static_cast<float>(best);
  }
}

void Referee::print(std::FILE* out) const {
  const RefereeReport& t = report_;
  std::fprintf(out,
               "  ground truth: %llu contacts (%llu of the robot's doing), min clearance %.2f m, closest person "
               "%.2f m, true path %.2f m, localization error max %.2f m\n",
               static_cast<unsigned long long>(t.contacts), static_cast<unsigned long long>(t.moving_contacts),
               t.min_clearance_m, t.min_person_distance_m, t.true_path_length_m, t.localization_error_max_m);
  if (t.relocalization_s >= 0) std::fprintf(out, "  relocalised %.2f s after the kidnapping\n", t.relocalization_s);
}

}  // namespace sen3bot::sim
