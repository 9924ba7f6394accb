// The report's canvas and figure: primitives land on the pixels they should, text is drawn
// where it is measured to be, and a case figure puts each layer where its data says.
#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sen3bot/figure/canvas.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"

namespace sen3bot::figure {
namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kRed{220, 0, 0};
constexpr Rgb kBlue{0, 0, 200};

int count(const Canvas& c, Rgb colour, int x0 = 0, int y0 = 0, int x1 = -1, int y1 = -1) {
  if (x1 < 0) x1 = c.width();
  if (y1 < 0) y1 = c.height();
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += c.at(x, y) == colour;
  return n;
}

// Anti-aliasing blends thin strokes with what is under them: these match a colour's blends.
bool near(Rgb a, Rgb b, int tol) {
  return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

template <typename Pred>
int count_if(const Canvas& c, Pred pred, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = std::max(y0, 0); y < std::min(y1, c.height()); ++y)
    for (int x = std::max(x0, 0); x < std::min(x1, c.width()); ++x) n += pred(c.at(x, y));
  return n;
}

bool greenish(Rgb p) { return p.g > p.r + 50 && p.g > p.b + 50; }
bool reddish(Rgb p) { return p.r > p.g + 50 && p.r > p.b + 20; }

int Round(double v) { return static_cast<int>(std::lround(v)); }
Rgb at(const Canvas& c, Px p) { return c.at(Round(p.x), Round(p.y)); }

TEST(Canvas, StartsAsTheBackgroundAndFillsClippedRectangles) {
  Canvas c(20, 10, kWhite);
  EXPECT_EQ(count(c, kWhite), 200);
  c.fill_rect(-5, 8, 10, 10, kRed);  // only x 0..4, y 8..9 are on the canvas
  EXPECT_EQ(count(c, kRed), 10);
  EXPECT_EQ(c.at(4, 9), kRed);
  EXPECT_EQ(c.at(5, 9), kWhite);
  EXPECT_EQ(c.at(4, 7), kWhite);
}

TEST(Canvas, ALineCoversItsCentreAndNothingFarFromIt) {
  Canvas c(60, 40, kWhite);
  c.line({10, 20}, {50, 20}, kRed, 3);
  for (int x = 12; x <= 48; ++x) EXPECT_EQ(c.at(x, 20), kRed) << x;
  EXPECT_EQ(c.at(30, 25), kWhite);
  EXPECT_EQ(c.at(30, 15), kWhite);
  EXPECT_EQ(c.at(55, 20), kWhite);
  c.polyline(std::vector<Px>{{5, 5}, {5, 35}, {25, 35}}, kBlue, 1);
  EXPECT_TRUE(near(c.at(5, 20), kBlue, 40));
  EXPECT_TRUE(near(c.at(15, 35), kBlue, 40));
  EXPECT_EQ(c.at(15, 5), kWhite);  // open: no closing edge
}

TEST(Canvas, DashesAlternateAlongTheWholePolyline) {
  Canvas c(120, 20, kWhite);
  // Two segments meeting at x = 35: the pattern carries on across the joint.
  c.dashed_polyline(std::vector<Px>{{0, 10}, {35, 10}, {100, 10}}, kRed, 1, 10, 10);
  for (int x : {3, 7, 23, 27, 43, 47, 63, 67, 83, 87}) EXPECT_TRUE(near(c.at(x, 10), kRed, 40)) << x;
  for (int x : {13, 17, 33, 37, 53, 57, 73, 77, 93, 97}) EXPECT_EQ(c.at(x, 10), kWhite) << x;
}

TEST(Canvas, PolygonsFillTheirInsideAndOutlinesOnlyTheirEdges) {
  Canvas c(50, 50, kWhite);
  const std::vector<Px> triangle{{5, 5}, {45, 5}, {5, 45}};
  c.fill_polygon(triangle, kBlue);
  EXPECT_EQ(c.at(10, 10), kBlue);
  EXPECT_EQ(c.at(40, 40), kWhite);
  Canvas o(50, 50, kWhite);
  const std::vector<Px> square{{10, 10}, {40, 10}, {40, 40}, {10, 40}};
  o.outline_polygon(square, kRed, 2);
  EXPECT_EQ(o.at(25, 10), kRed);
  EXPECT_EQ(o.at(10, 25), kRed);  // closed: the edge back to the first vertex
  EXPECT_EQ(o.at(25, 25), kWhite);
}

TEST(Canvas, DiscsAndRings) {
  Canvas c(60, 30, kWhite);
  c.disc({15, 15}, 8, kRed);
  c.ring({45, 15}, 8, kBlue, 2);
  EXPECT_EQ(c.at(15, 15), kRed);
  EXPECT_EQ(c.at(20, 15), kRed);
  EXPECT_EQ(c.at(15, 26), kWhite);
  EXPECT_EQ(c.at(45, 15), kWhite);  // a ring's middle stays empty
  EXPECT_EQ(c.at(53, 15), kBlue);
  EXPECT_EQ(c.at(45, 7), kBlue);
}

TEST(Canvas, TextIsDrawnInsideTheBoxItIsMeasuredAt) {
  Canvas c(200, 40, kWhite);
  const int w = Canvas::text_width("case 2/3", 0.5), h = Canvas::text_height(0.5);
  EXPECT_GT(w, Canvas::text_width("case", 0.5));
  EXPECT_GT(h, 6);
  EXPECT_LT(h, 16);
  c.text({20, 30}, "case 2/3", kBlue, 0.5);
  int inside = 0, outside = 0;
  for (int y = 0; y < c.height(); ++y)
    for (int x = 0; x < c.width(); ++x) {
      if (c.at(x, y) == kWhite) continue;
      // "/" reaches a little below the baseline.
      const bool in_box = x >= 19 && x <= 21 + w && y >= 30 - h - 2 && y <= 30 + h / 2;
      (in_box ? inside : outside) += 1;
    }
  EXPECT_GT(inside, 40);
  EXPECT_EQ(outside, 0);
  // Solid glyph cores, not only faint anti-aliased edges.
  EXPECT_GT(count_if(c, [](Rgb p) { return p.b > 150 && p.r < 90; }, 0, 0, c.width(), c.height()), 10);
}

TEST(Canvas, AHaloClearsAroundTheGlyphs) {
  Canvas c(100, 30, kWhite);
  c.fill_rect(0, 0, 100, 30, kRed);
  Canvas plain = c;
  plain.text({10, 20}, "12", kBlue, 0.5, 1, false);
  c.text({10, 20}, "12", kBlue, 0.5, 1, true);
  // The halo is drawn in the canvas' background (white), over the red.
  EXPECT_EQ(count(plain, kWhite), 0);
  EXPECT_GT(count(c, kWhite), 20);
}

TEST(Canvas, WritesAPng) {
  Canvas c(8, 4, kRed);
  const std::string path = ::testing::TempDir() + "canvas_test.png";
  ASSERT_TRUE(c.write_png(path));
  std::ifstream f(path, std::ios::binary);
  char signature[8] = {};
  f.read(signature, 8);
  EXPECT_EQ(std::string(signature + 1, 3), "PNG");
  std::remove(path.c_str());
  EXPECT_FALSE(c.write_png("/nonexistent-folder/x.png"));
}

TEST(View, MapsMetresWithYUpToPixelsWithYDown) {
  const View v{1.0, 2.0, 50.0, 10.0, 300.0};
  const Px origin = v(1.0, 2.0);
  EXPECT_DOUBLE_EQ(origin.x, 10.0);
  EXPECT_DOUBLE_EQ(origin.y, 300.0);
  const Px p = v(3.0, 3.0);
  EXPECT_DOUBLE_EQ(p.x, 110.0);
  EXPECT_DOUBLE_EQ(p.y, 250.0);
}

TEST(ScaleBar, ARoundLengthOfAtLeastSixtyPixels) {
  EXPECT_DOUBLE_EQ(scale_bar_length_m(80), 1.0);
  EXPECT_DOUBLE_EQ(scale_bar_length_m(40), 2.0);
  EXPECT_DOUBLE_EQ(scale_bar_length_m(200), 0.5);
  EXPECT_DOUBLE_EQ(scale_bar_length_m(10), 10.0);
  Canvas c(200, 40, kWhite);
  draw_scale_bar(c, 20, 5, 80);  // 1 m = 80 px: ink 20..59, paper 60..99, frame at 100
  for (int x = 20; x < 60; ++x) EXPECT_EQ(c.at(x, 8), colours::kInk) << x;
  for (int x = 60; x < 100; ++x) EXPECT_EQ(c.at(x, 8), kWhite) << x;
  EXPECT_EQ(c.at(100, 8), colours::kInk);
  EXPECT_EQ(c.at(80, 4), colours::kInk);
  EXPECT_EQ(c.at(80, 11), colours::kInk);
  EXPECT_EQ(c.at(19, 8), kWhite);
  // "1 m" under its end.
  EXPECT_GT(count_if(c, [](Rgb p) { return p.r + p.g + p.b < 400; }, 90, 14, 140, 30), 5);
}

TEST(RobotInstants, EveryMetreAndTheLastPose) {
  std::vector<RobotAt> poses;
  for (int i = 0; i <= 13; ++i) poses.push_back({static_cast<double>(i), {0.25 * i, 0, 0}});
  std::vector<double> times;
  for (const RobotAt& r : robot_instants(poses, 1.0)) times.push_back(r.t_s);
  // 4, 8 and 12 are a metre apart; 13 is a quarter metre past 12 and takes its place.
  EXPECT_EQ(times, (std::vector<double>{0, 4, 8, 13}));
  poses.resize(11);  // to 2.5 m: the last is half a metre past 8 and is added
  times.clear();
  for (const RobotAt& r : robot_instants(poses, 1.0)) times.push_back(r.t_s);
  EXPECT_EQ(times, (std::vector<double>{0, 4, 8, 10}));
  EXPECT_TRUE(robot_instants({}, 1.0).empty());
}

// A 4 x 3 m map, 10 cm cells, with a wall block at x 1.0..1.5 m, y 2.0..2.5 m and an unknown
// cell at the top right.
nav::OccupancyMap test_map() {
  nav::OccupancyMap map(40, 30, 0.1, 0.0, 0.0);
  for (int row = 0; row < 30; ++row)
    for (int col = 0; col < 40; ++col) map.set(col, row, 0);
  for (int row = 20; row < 25; ++row)
    for (int col = 10; col < 15; ++col) map.set(col, row, 100);
  map.set(39, 29, -1);
  return map;
}

CaseFigure test_figure(const nav::OccupancyMap& map) {
  CaseFigure f;
  f.title = "case 1/1: test";
  f.description = "a test case";
  f.result = "goal reached in 1.0 s, 0 contacts";
  f.passed = true;
  f.map = &map;
  f.start = {0.5, 0.5, 0};
  f.goals = {{3.5, 0.5}};
  f.driven = {{0.5, 0.5}, {3.5, 0.5}};
  return f;
}

TEST(CaseFigure, TheMapAndThePathsWhereTheirDataSays) {
  const nav::OccupancyMap map = test_map();
  CaseFigure f = test_figure(map);
  f.plans = {{{0.5, 1.5}, {3.5, 1.5}}};
  f.estimated = {{0.5, 1.0}, {3.5, 1.0}};
  f.waypoints = {{2.0, 2.8}};
  const Canvas c = draw_case_figure(f);
  const View v = figure_view(f);
  EXPECT_DOUBLE_EQ(v.px_per_m, 80.0);
  EXPECT_EQ(at(c, v(1.25, 2.25)), colours::kWall);
  EXPECT_EQ(at(c, v(1.75, 2.25)), colours::kPaper);
  EXPECT_EQ(at(c, v(3.95, 2.95)), colours::kUnknown);
  EXPECT_EQ(at(c, v(2.0, 0.5)), colours::kDriven);
  EXPECT_EQ(at(c, v(2.0, 1.5)), colours::kPlan);
  EXPECT_EQ(at(c, v(2.0, 2.8)), colours::kWaypoint);
  // The estimate is dashed: along its line both its colour and the paper show.
  int dash = 0, gap = 0;
  for (double x = 1.0; x < 3.0; x += 0.01) {
    const Rgb p = at(c, v(x, 1.0));
    dash += p == colours::kEstimated;
    gap += p == colours::kPaper;
  }
  EXPECT_GT(dash, 80);
  EXPECT_GT(gap, 15);  // a solid line would leave none
  // Start: a ring around the start; goal: a dark disc with a paper ring inside.
  EXPECT_EQ(at(c, {v(0.5, 0.5).x + 11, v(0.5, 0.5).y}), colours::kStart);
  const Px goal = v(3.5, 0.5);
  EXPECT_EQ(at(c, goal), colours::kGoal);
  EXPECT_TRUE(near(at(c, {goal.x + 4, goal.y}), colours::kPaper, 10));
  EXPECT_EQ(at(c, {goal.x + 7, goal.y}), colours::kGoal);
  // The result line, in the header above the plot, in the passed colour.
  const int header_bottom = Round(v(0, 3.0).y) - 30;
  EXPECT_GT(count_if(c, greenish, 0, 0, c.width(), header_bottom), 50);
  EXPECT_EQ(count_if(c, reddish, 0, 0, c.width(), header_bottom), 0);
}

TEST(CaseFigure, ADrivenPathBreaksWhereTheRobotWasCarried) {
  const nav::OccupancyMap map = test_map();
  CaseFigure f = test_figure(map);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  f.driven = {{0.5, 0.5}, {1.5, 0.5}, {nan, nan}, {2.5, 2.5}, {3.5, 2.5}};
  const Canvas c = draw_case_figure(f);
  const View v = figure_view(f);
  EXPECT_EQ(at(c, v(1.0, 0.5)), colours::kDriven);
  EXPECT_EQ(at(c, v(3.0, 2.5)), colours::kDriven);
  EXPECT_EQ(at(c, v(2.0, 1.5)), colours::kPaper);  // halfway along the carry: nothing drawn
}

TEST(CaseFigure, TheRobotsFootprintOrientedAtItsPose) {
  const nav::OccupancyMap map = test_map();
  CaseFigure f = test_figure(map);
  f.driven.clear();
  f.robot = {{5.0, {2.0, 1.5, std::numbers::pi / 2}}};  // facing +y: 0.455 m long along y
  const Canvas c = draw_case_figure(f);
  const View v = figure_view(f);
  EXPECT_EQ(at(c, v(2.0, 1.5 + 0.2275)), colours::kRobot);   // front edge
  EXPECT_EQ(at(c, v(2.0, 1.5 - 0.2275)), colours::kRobot);   // rear edge
  EXPECT_EQ(at(c, v(2.0 + 0.1905, 1.5)), colours::kRobot);   // side
  EXPECT_EQ(at(c, v(2.0, 1.5 + 0.12)), colours::kRobot);     // the heading line, forward
  EXPECT_EQ(at(c, v(2.0, 1.5 - 0.12)), colours::kPaper);     // nothing behind the centre
  EXPECT_EQ(at(c, v(2.0 + 0.2275, 1.5)), colours::kPaper);     // where an unturned front edge would be
  // Its time label beside it, outside the footprint's own square.
  const auto robot_ink = [](Rgb p) { return p.r > p.g + 50 && p.g == p.b; };
  const int around = count_if(c, robot_ink, Round(v(1.5, 0).x), Round(v(0, 2.0).y), Round(v(2.5, 0).x), Round(v(0, 1.0).y));
  const int body = count_if(c, robot_ink, Round(v(1.75, 0).x), Round(v(0, 1.75).y), Round(v(2.25, 0).x), Round(v(0, 1.25).y));
  EXPECT_GT(around - body, 20);
}

TEST(CaseFigure, PeopleBoxesAndContactsAndTheLegendListsWhatIsDrawn) {
  const nav::OccupancyMap map = test_map();
  CaseFigure without = test_figure(map);
  without.passed = false;
  const Canvas plain = draw_case_figure(without);
  EXPECT_EQ(count(plain, colours::kBox), 0);
  EXPECT_EQ(count(plain, colours::kPerson), 0);
  EXPECT_EQ(count(plain, colours::kContact), 0);
  EXPECT_GT(count_if(plain, reddish, 0, 0, plain.width(), Round(figure_view(without).bottom_px) - 240), 50);
  EXPECT_EQ(count_if(plain, greenish, 0, 0, plain.width(), plain.height()), 0);

  CaseFigure f = test_figure(map);
  MoverTrack box;
  box.path = {{3.0, 2.0}};
  box.square = true;
  MoverTrack person;
  person.person = true;
  person.size_m = 0.4;
  person.path = {{0.5, 2.7}, {3.5, 2.7}};
  person.marks = {{3.0, {2.5, 2.7}}};
  f.movers = {box, person};
  f.contacts = {{{1.0, 0.5}, 4.0, true}};
  const Canvas c = draw_case_figure(f);
  const View v = figure_view(f);
  EXPECT_EQ(at(c, v(3.0, 2.0)), colours::kBox);
  EXPECT_EQ(at(c, v(3.15, 2.15)), colours::kBox);  // 40 cm square
  EXPECT_EQ(at(c, v(1.0, 2.7)), colours::kPerson);
  EXPECT_EQ(at(c, v(2.5 + 0.2, 2.7 - 0.02)), colours::kPerson);  // the ring at t = 3
  EXPECT_EQ(at(c, v(1.0, 0.5)), colours::kContact);
  // The legend, right of the plot, gains a swatch for each.
  const int legend_x = Round(v(4.0, 0).x) + 1;
  for (const Rgb colour : {colours::kBox, colours::kPerson, colours::kContact}) {
    EXPECT_GT(count(c, colour, legend_x, 0, c.width(), c.height()), 10);
    EXPECT_EQ(count(plain, colour, legend_x, 0, plain.width(), plain.height()), 0);
  }
}

}  // namespace
}  // namespace sen3bot::figure
