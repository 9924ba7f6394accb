#pragma once
// The referee: judges a run from the ground truth, outside the firmware. It sees every world
// step and, when given one, the firmware's pose estimate, and keeps what a report says about
// the real world: contacts, clearance, the closest person, the true path and how far the
// estimate strayed from the truth.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>

#include "sen3bot/msg/messages.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/sim/simulation.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::sim {

// Above this speed the robot counts as moving: a contact then is of its doing.
inline constexpr double kRobotMovingSpeedM_s = 0.02;

struct RefereeReport {
  std::uint64_t contacts = 0;         // times the footprint started to overlap something
  std::uint64_t moving_contacts = 0;  // of those, the robot moving towards what it touched: collisions
  double min_clearance_m = 1e9;
  double min_person_distance_m = 1e9;
  double true_path_length_m = 0;
  double localization_error_max_m = 0;  // estimate vs truth, while the robot moved
  // From a kidnapping to the first estimate after which every estimate is within
  // kRelocalizedM and kRelocalizedRad of the truth; < 0 without a kidnapping or while not back.
  double relocalization_s = -1;
  // The firmware's people (watch_people) against the true ones: each published person placed
  // within kPersonFreshS (by a box or the laser) whose nearest true person is
  // kPersonRangeMinM..kPersonRangeMaxM from the robot adds its error to person_errors(); one
  // farther than kPersonMatchM from every true person is a false one.
  std::uint64_t people_judged = 0;
  std::uint64_t false_people = 0;
};

// A true pose at a world time (the simulation clock's seconds).
struct TimedPose {
  double t_s = 0;
  msg::Pose2D pose;
  bool moving = false;  // for a contact: whether the robot itself was moving
  bool person = false;  // for a contact: whether it was with a person (else the map or a box)
};

// Where a person (a world mover) truly was at a world time.
struct PersonAt {
  double t_s = 0;
  std::uint32_t mover = 0;
  msg::Point2D at;
};

// How close to a person the robot's centre may come before it is in the person's cage, as the
// reports judge it: the person's body radius, the default cage safety radius (0.5 m) and the
// robot's half width (0.19 m), since its footprint must stay out.
[[nodiscard]] constexpr double judged_cage_reach_m(double person_radius_m) noexcept {
  return person_radius_m + 0.5 + 0.19;
}

class Referee {
 public:
  static constexpr std::size_t kMaxTrack = 4096;
  static constexpr std::size_t kMaxPoses = 4096;  // at kPoseIntervalS: 17 minutes
  static constexpr double kPoseIntervalS = 0.25;
  static constexpr std::size_t kMaxContacts = 64;
  static constexpr std::size_t kMaxPersonPath = 16384;  // two walkers for 34 minutes
  static constexpr double kRelocalizedM = 0.3;
  static constexpr double kRelocalizedRad = 10.0 * 3.14159265358979323846 / 180.0;

  static constexpr std::size_t kMaxPersonErrors = 16384;
  static constexpr double kPersonRangeMinM = 1.0;
  static constexpr double kPersonRangeMaxM = 6.0;
  static constexpr double kPersonMatchM = 1.0;
  static constexpr double kPersonFreshS = 0.3;  // a person last placed longer ago is not judged

  // The firmware's pose estimate, compared with the truth at every step; null: not judged.
  void watch_estimate(const tasks::Topic<msg::PoseEstimate>* estimate) noexcept { estimate_ = estimate; }
  // The firmware's people, each message against the true people of the step after it.
  void watch_people(const tasks::Topic<msg::People>* people) noexcept { people_ = people; }
  // Every world step; never allocates.
  void observe(const GroundTruth& truth) noexcept;

  [[nodiscard]] const RefereeReport& report() const noexcept { return report_; }
  void print(std::FILE* out) const;
  // The true driven path, a point per 5 cm moved; a non-finite point where the robot was
  // carried off (a kidnapping), so nothing draws the carry as driving.
  [[nodiscard]] std::span<const msg::Point2D> track() const noexcept { return {track_.data(), track_count_}; }
  // The true pose every kPoseIntervalS, with its heading: where a figure draws the robot.
  [[nodiscard]] std::span<const TimedPose> poses() const noexcept { return {poses_.data(), pose_count_}; }
  // The published estimate's path, a point per 5 cm moved (valid estimates only).
  [[nodiscard]] std::span<const msg::Point2D> estimate_track() const noexcept {
    return {estimate_track_.data(), estimate_track_count_};
  }
  // Each judged person's position error (m), the first kMaxPersonErrors of them.
  [[nodiscard]] std::span<const float> person_errors() const noexcept {
    return {person_errors_.data(), person_error_count_};
  }
  // The true people (GroundTruth::people) with every pose of poses(): their paths, however
  // they were moved; the first kMaxPersonPath samples.
  [[nodiscard]] std::span<const PersonAt> person_path() const noexcept { return {person_path_.data(), person_path_count_}; }
  // The true pose where each contact began, the first kMaxContacts of them.
  [[nodiscard]] std::span<const TimedPose> contact_poses() const noexcept { return {contacts_.data(), contact_count_}; }

 private:
  void judge_people(const GroundTruth& truth) noexcept;

  const tasks::Topic<msg::PoseEstimate>* estimate_ = nullptr;
  std::uint64_t estimate_sequence_ = 0;
  RefereeReport report_;
  bool have_last_ = false;
  msg::Pose2D last_;
  std::array<msg::Point2D, kMaxTrack> track_{};
  std::size_t track_count_ = 0;
  std::array<TimedPose, kMaxPoses> poses_{};
  std::size_t pose_count_ = 0;
  std::array<msg::Point2D, kMaxTrack> estimate_track_{};
  std::size_t estimate_track_count_ = 0;
  std::array<PersonAt, kMaxPersonPath> person_path_{};
  std::size_t person_path_count_ = 0;
  std::array<TimedPose, kMaxContacts> contacts_{};
  std::size_t contact_count_ = 0;
  hal::Nanos close_since_ns_ = -1;  // after a kidnapping: since when every estimate was close
  const tasks::Topic<msg::People>* people_ = nullptr;
  std::uint64_t people_sequence_ = 0;
  std::array<float, kMaxPersonErrors> person_errors_{};
  std::size_t person_error_count_ = 0;
};

}  // namespace sen3bot::sim
