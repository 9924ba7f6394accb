// The named scenarios of `sen3bot-sim sim` (sim_scenarios.hpp): where the robot starts and
// goes, its safe path, and each case's movers, kidnap and safety I/O events.
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <utility>
#include <vector>

#include "sim_scenarios.hpp"

namespace sen3bot::sim::scenario {

namespace {

SimIoEvent io_inputs(double at_s, std::uint8_t inputs) { return {at_s, SimIoEvent::What::inputs, inputs}; }
SimIoEvent io_fault(double at_s, SimIoEvent::What what) { return {at_s, what, 0}; }
// config/sim.yaml's wiring: the e-stop chain on input 1 (active-low), reset on 2, a bumper on 3.
constexpr std::uint8_t kChainClosed = 0x01, kEstopPressed = 0x00, kResetPressed = 0x03, kBumperHit = 0x05;
// The reset button pressed for 0.2 s at at_s.
std::vector<SimIoEvent> reset_at(double at_s) {
  return {io_inputs(at_s, kResetPressed), io_inputs(at_s + 0.2, kChainClosed)};
}
std::vector<SimIoEvent> events(std::initializer_list<std::vector<SimIoEvent>> parts) {
  std::vector<SimIoEvent> all;
  for (const auto& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

world::MoverScript box_at(double x_m, double y_m, double appear_s) {
  world::MoverScript box;
  box.path = {{x_m, y_m}};
  box.size_m = 0.4;  // the thesis' obstacle: a 40 cm box
  box.shape = world::MoverShape::square;
  box.appear_time_s = appear_s;
  return box;
}

}  // namespace

std::vector<Scenario> all() {
  const msg::Pose2D thesis_start{4.0, 7.0, -std::numbers::pi / 2};
  return {
      {"thesis-sgp",
       "the thesis' supervised-planning test: (4, 7) m to (2.5, 2) m on the lab map along the safe path",
       thesis_start,
       {{2.5, 2.0}},
       "maps/lab_curve.yaml",
       "",
       {{"no-obstacle", "nothing unexpected on the way", {}},
        {"obstacle-before-planning", "a 40 cm box on the safe path, there from the start", {box_at(3.3, 5.37, 0.0)}},
        {"obstacle-during-motion", "a 40 cm box that appears on the safe path while the robot drives",
         {box_at(2.81, 3.25, 8.2)}}},
       false,
       true},
      {"person-crossing",
       "the main mission: (2.5, 2) m to (4, 7) m and back while a worker crosses the upper area",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "",
       "",
       {{"worker", "a person walking across the robot's way, back and forth",
         {world::walking_person({{5.0, 5.3}, {1.0, 5.3}}, 0.6, 6.0)}}}},
      {"people-crossing",
       "the main mission among people: (2.5, 2) m to (4, 7) m and back on the lab's safe curve, two workers "
       "crossing its way at 0.6 and 1.0 m/s, found by the camera and the laser and caged (each seed starts "
       "them at other points of their walks)",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "maps/lab_curve.yaml",
       "",
       {{"two-workers", "one across the upper area, one across the lower area",
         {world::walking_person({{6.8, 5.5}, {0.8, 5.5}}, 0.6, 0.0), world::walking_person({{1.8, 3.0}, {6.8, 3.0}}, 1.0, 0.0)}}},
       true},
      {"kidnapped",
       "(2.5, 2) m to (4, 7) m and back; on the way back the robot is carried into the lower work area, its odometry "
       "not told",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "",
       "",
       {{"carried-downstairs",
         "at t = 19 s, leaving (4, 7) m in the upper storage area, carried to (5, 3.5) m in the lower work area, facing east",
         {},
         {19.0, {5.0, 3.5, 0.0}}}}},
      {"estop",
       "the main mission, (2.5, 2) m to (4, 7) m and back, with the CAN safety I/O node's e-stop chain: each case stops "
       "the robot while it drives, and it goes on only once the cause is gone and the reset button was pressed",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "",
       "",
       {{"estop-pressed", "the e-stop pressed at t = 6 s, released at 9 s, reset at 11 s", {}, {},
         events({{io_inputs(6.0, kEstopPressed), io_inputs(9.0, kChainClosed)}, reset_at(11.0)})},
        {"bumper-hit", "a bumper pressed for 0.3 s at t = 6 s, reset at 8 s", {}, {},
         events({{io_inputs(6.0, kBumperHit), io_inputs(6.3, kChainClosed)}, reset_at(8.0)})},
        {"node-silent", "the I/O node silent from t = 6 s to 7 s (a cut cable), reset at 9 s", {}, {},
         events({{io_fault(6.0, SimIoEvent::What::silent), io_fault(7.0, SimIoEvent::What::talking)}, reset_at(9.0)})},
        {"bus-off", "the CAN bus off from t = 6 s to 6.5 s, reset at 8 s", {}, {},
         events({{io_fault(6.0, SimIoEvent::What::bus_off), io_fault(6.5, SimIoEvent::What::bus_on)}, reset_at(8.0)})},
        {"node-reboot", "the I/O node reboots at t = 6 s (configured and started again), reset at 8 s", {}, {},
         events({{io_fault(6.0, SimIoEvent::What::reboot)}, reset_at(8.0)})}}},
      {"osgp",
       "the source's online-SGP cases: (4, 7) m to (2.5, 2) m on the lab's safe curve, with people found by the camera "
       "and the laser and kept in cages",
       thesis_start,
       {{2.5, 2.0}},
       "maps/lab_curve.yaml",
       "",
       {{"person-on-path", "a person standing by the right-hand rack, 0.45 m beside the safe path: re-plan, pass at a distance",
         {world::standing_person(4.3, 5.7)}},
        {"person-far", "a person standing 1.3 m beyond the goal, off the route: caged, no re-plan",
         {world::standing_person(3.3, 1.0)}},
        {"box-on-path", "a 40 cm box where the person of case 1 stands: the local planner goes round it, no re-plan",
         {box_at(4.3, 5.7, 0.0)}}},
       true},
  };
}

}  // namespace sen3bot::sim::scenario
