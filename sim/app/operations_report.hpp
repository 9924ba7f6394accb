#pragma once
// The figures of `sen3bot-sim experiment operations` (cmd_operations.cpp): the confusion
// matrices, the progressive curve and example paths on the map. docs/cobot/recognition.md.
#include <string>
#include <vector>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/recognizer.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/figure/canvas.hpp"

namespace sen3bot::sim::operations {

// One evaluated classifier, as the figures label it.
struct Labelled {
  std::string label;  // "order-encoded", "occupancy only (thesis input)"
  cobot::Evaluation evaluation;
};

// A matrix per classifier side by side: rows the true operation, columns the recognised one,
// cells shaded by the row's fraction and labelled with the count.
[[nodiscard]] figure::Canvas draw_confusion(const std::string& title, const std::string& subtitle,
                                            const std::vector<Labelled>& results);

// Per classifier, against the percentage of the path walked: the mean probability of the right
// operation (solid) and the fraction of paths where it is above the bar (dashed); the bar and
// the 60 % mark as guides.
[[nodiscard]] figure::Canvas draw_progressive(const std::string& title, const std::string& subtitle,
                                              const std::vector<Labelled>& results, double bar);

// The map in metres with the stations and one path per operation.
struct ExamplePath {
  std::string label;  // "name", or "name\nwhat it visits" (a second, grey line)
  std::vector<float> xy;
};
[[nodiscard]] figure::Canvas draw_example_paths(const std::string& title, const std::string& subtitle,
                                                const nav::OccupancyMap& map, const cobot::OperationsConfig& config,
                                                const std::vector<ExamplePath>& paths);

}  // namespace sen3bot::sim::operations
