#pragma once
// Statistics of people's walks, to put simulated walkers side by side with the recordings
// (docs/crowd.md, "Walkers against the recordings"). Walks are held as a Recording: tracks of
// positions sampled at a fixed period, the recordings' 0.4 s. A simulated crowd is sampled at
// the same period into the same form (sample_crowd), so both go through the same code.
//
//   speed          |p[k+1] - p[k]| / dt over consecutive samples of a track (every pair: what
//                  the pedestrian README's median speeds count)
//   walking speed  the pairs at or above walking_m_s (0.2 m/s, 8 cm per 0.4 s). The recordings'
//                  speeds have a standing peak below 0.1 m/s (hotel: 1151 of 6154 pairs, 1045 of
//                  them exactly still: people waiting for the tram) and a trough from 0.15 to
//                  0.45 m/s; any bound in the trough moves the median by under 2 %
//   free speed     walking pairs with nobody within free_m (2 m centre to centre, beyond Hall's
//                  personal zone between two 0.25 m bodies) at either sample: the unhindered
//                  walking speed that desired speeds are drawn from (Moussaïd et al. 2009)
//   nearest        per person per sample, centre to centre, at samples with >= 2 people
//   stranger       the nearest person not walking alongside: a companion is within free_m, and
//                  both walk with velocities (the step to the next sample) within companion_m_s
//                  of each other. Groups walk together; simulated walkers do not form them
//   curvature      per triple of consecutive samples whose two steps are both walking: 1 / the
//                  radius of the circle through the three points (Menger curvature,
//                  2 sin(turn) / |p[k+1] - p[k-1]|): exactly 1/R on a circle of radius R, 0 on
//                  a straight line, about the turning angle per metre walked for small turns
//   smooth curvature  the same over samples smooth_span apart (k, k + 3, k + 6: 1.2 s), both
//                  steps walking on average. At 0.4 s the recordings' artefacts dominate: hotel's
//                  annotation jitter turns a straight walk by some 0.1 rad a step (median 0.17 /m,
//                  0.04 /m at 1.2 s), and zara's positions are interpolated between key frames, so
//                  most 0.4 s triples are exactly straight (median 0.003 /m, 0.05 /m at 1.2 s)
//
// Pairs and triples use only samples one period apart (a track's gap is skipped); samples
// belong to one moment when their times round to the same multiple of the period.
#include <cstddef>
#include <cstdint>

#include "sen3bot/crowd/crowd.hpp"
#include "sen3bot/crowd/metrics.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::crowd {

inline constexpr double kWalkSamplePeriodS = 0.4;  // the recordings' annotation step

struct WalkStatsOptions {
  double period_s = kWalkSamplePeriodS;
  double walking_m_s = 0.2;    // slower is standing
  double free_m = 2.0;         // nobody nearer: free walking; also a companion's range
  double companion_m_s = 0.3;  // velocities this close: walking alongside
  std::size_t smooth_span = 3; // samples between the points of a smooth-curvature triple (0 is 1)
};

struct WalkStats {
  std::size_t moments = 0;        // sampled times with at least one person
  Quartiles people;               // per moment with at least one person
  Quartiles speed_m_s;            // every pair
  Quartiles walking_speed_m_s;    // pairs at or above walking_m_s
  Quartiles free_speed_m_s;       // walking pairs with nobody within free_m
  Quartiles nearest_m;            // per person per moment with >= 2 people
  Quartiles stranger_nearest_m;   // nearest non-companion (samples that have one)
  double companion_share = 0.0;   // of the nearest_m samples: the nearest is a companion
  Quartiles curvature_per_m;      // per walking triple of consecutive samples
  Quartiles smooth_curvature_per_m;  // per walking triple smooth_span samples apart
};

// Statistics of the walks in `walks` (its tracks; the name, first frame and frame step are not
// used). Allocates; NaN quartiles where there is nothing to count (everything, for a period that
// is not positive and finite; a sample at a time that is not finite is in no moment).
[[nodiscard]] WalkStats walk_stats(const Recording& walks, const WalkStatsOptions& options = {});

// Samples a crowd every period_s from its current time for duration_s (the first sample at the
// crowd's current time, the last at or before the end), without a robot: each run of samples in
// which a person stays visible is a track with person_id the person's index. Sample times are
// the crowd's time at each sample. Errors: a period or duration not positive and finite.
[[nodiscard]] Result<Recording> sample_crowd(Crowd& crowd, double duration_s, double period_s = kWalkSamplePeriodS);

struct MatchedCrowdOptions {
  std::size_t people = 0;    // present at once; 0: the recording's median people per moment
  double duration_s = 300.0; // walkers are planned to keep the count up this long
  // Of the people, the share walking in pairs (side by side, kCompanionGapM apart, one route
  // and pace, a group of the social force model); the rest walk alone.
  double pair_share = 0.0;
  // Routes as the recording's people walked them: each walk from the first to the last place
  // of a recorded track (drawn at random, 0.2 m of jitter), where people enter and leave (doors,
  // pavements); false: between random points of the extent's sides.
  bool recorded_routes = false;
};
inline constexpr double kCompanionGapM = 0.7;  // centre to centre, shoulder to shoulder plus a little

// Social walkers at a recording's density: the floor is the extent of every annotation with
// walls on its border; `people` walkers are present at any time. Each walks from 0.5 m inside
// one side to a uniform point 0.5 m inside another side (at least 2 m away), at a desired speed
// drawn as the benchmark's scenes draw it (normal 1.3 +- 0.26 m/s, drawn again outside
// [0.5, 2.0]), and leaves at its goal; the next walker of its slot appears at the moment it
// would nominally arrive (its length at its desired speed, plus the relaxation time lost
// starting from rest, less the goal reach), so the count holds up to that estimate. The first
// walker of each slot starts at a uniform point of its walk, so the scene starts as it goes on.
// A walker is drawn again when it would appear within r_i + r_j + 0.2 m of where another
// nominally is. Pure and seeded (random.hpp). Errors: a recording without samples or with a
// flat extent, no people, more walkers than kMaxWalkers (capacity: shorten the duration), a
// duration not positive and finite, no room for a walker in 1000 draws (capacity).
[[nodiscard]] Result<CrowdConfig> matched_crowd(const Recording& recording, std::uint64_t seed,
                                                const MatchedCrowdOptions& options = {});

}  // namespace sen3bot::crowd
