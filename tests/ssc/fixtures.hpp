#pragma once
// Small builders for the centre's tests: rectangles, areas, homes.
#include <initializer_list>

#include "sen3bot/ssc/site.hpp"

namespace sen3bot::ssc::testing {

inline Polygon rect(double x0, double y0, double x1, double y1) {
  Polygon p;
  (void)p.push_back({x0, y0});
  (void)p.push_back({x1, y0});
  (void)p.push_back({x1, y1});
  (void)p.push_back({x0, y1});
  return p;
}

inline Area area(AreaId id, const char* name, AreaType type, const Polygon& outline,
                 std::initializer_list<Pose> sentries = {}) {
  Area a;
  a.id = id;
  a.name = name;
  a.type = type;
  a.outline = outline;
  for (const Pose& s : sentries) (void)a.sentries.push_back(s);
  return a;
}

inline RobotHome home(RobotId id, const char* name, Pose pose, AreaId overlooks = kNone) {
  RobotHome h;
  h.robot = id;
  h.name = name;
  h.pose = pose;
  h.overlooks = overlooks;
  return h;
}

}  // namespace sen3bot::ssc::testing
