#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "sen3bot/nav/map.hpp"

namespace sen3bot::nav {
namespace {

std::string pgm_p5(int w, int h, const std::vector<unsigned char>& pixels) {
  std::string s = "P5\n# comment\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
  s.append(pixels.begin(), pixels.end());
  return s;
}

MapYaml base_yaml() {
  MapYaml y;
  y.image = "x.pgm";
  y.resolution_m = 0.05;
  y.occupied_thresh = 0.65;
  y.free_thresh = 0.25;
  return y;
}

TEST(MapYaml, ParsesAllKeys) {
  auto y = parse_map_yaml(
      "image: \"maps/a b.pgm\"  # comment\nresolution: 0.1\norigin: [1.5, -2, 0.25]\n"
      "occupied_thresh: 0.7\nfree_thresh: 0.2\nnegate: 1\nmode: scale\n",
      "t.yaml");
  ASSERT_TRUE(y.ok()) << y.error().c_str();
  EXPECT_EQ(y->image, "maps/a b.pgm");
  EXPECT_DOUBLE_EQ(y->resolution_m, 0.1);
  EXPECT_DOUBLE_EQ(y->origin_x_m, 1.5);
  EXPECT_DOUBLE_EQ(y->origin_y_m, -2.0);
  EXPECT_DOUBLE_EQ(y->origin_yaw_rad, 0.25);
  EXPECT_DOUBLE_EQ(y->occupied_thresh, 0.7);
  EXPECT_DOUBLE_EQ(y->free_thresh, 0.2);
  EXPECT_TRUE(y->negate);
  EXPECT_EQ(y->mode, MapMode::scale);
}

TEST(MapYaml, ErrorsNameFileAndKey) {
  struct Case {
    const char* text;
    const char* expect;
  } cases[] = {
      {"resolution: 0.1\norigin: [0,0,0]\n", "image: missing"},
      {"image: a.pgm\norigin: [0,0,0]\n", "resolution: missing"},
      {"image: a.pgm\nresolution: 0.1\n", "origin: missing"},
      {"image: a.pgm\nresolution: -1\norigin: [0,0,0]\n", "resolution: expected a number > 0"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0]\n", "origin: expected [x, y, yaw]"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0,0,1]\n", "origin: expected [x, y, yaw]"},
      {"image: a.pgm\nresolution: 0.1\norigin: 0\n", "origin: expected [x, y, yaw]"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,x,0]\n", "origin[1]: expected a number, got 'x'"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0,0]\nnegate: 2\n", "negate: expected 0, false, 1 or true, got '2'"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0,0]\nmode: fancy\n", "mode: expected trinary, scale or raw, got 'fancy'"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0,0]\noccupied_thresh: 1.5\n", "occupied_thresh: value 1.5 is outside [0, 1]"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0,0]\nfree_thresh: 0.9\n", "free_thresh: 0.9 must be below occupied_thresh 0.65"},
      {"image: a.pgm\nresolution: 0.1\norigin: [0,0,0]\ncolour: red\n", "colour: unknown key"},
      {"image: a.pgm\nresolution 0.1\n", "resolution 0.1: unknown key"},
  };
  for (const auto& c : cases) {
    auto y = parse_map_yaml(c.text, "site.yaml");
    ASSERT_FALSE(y.ok()) << c.text;
    const std::string msg(y.error().message());
    EXPECT_NE(msg.find("site.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_NE(msg.find("(line "), std::string::npos) << msg;
  }
}

TEST(Pgm, ReadsP5AndP2Alike) {
  auto a = parse_pgm(pgm_p5(3, 2, {0, 100, 255, 1, 2, 3}), "a.pgm");
  auto b = parse_pgm("P2\n3 2\n# mid comment\n255\n0 100 255\n1 2 3\n", "b.pgm");
  ASSERT_TRUE(a.ok()) << a.error().c_str();
  ASSERT_TRUE(b.ok()) << b.error().c_str();
  EXPECT_EQ(a->pixels, b->pixels);
  EXPECT_EQ(a->width, 3);
  EXPECT_EQ(a->height, 2);
}

TEST(Pgm, SixteenBitRaster) {
  std::string s = "P5 2 1 1000\n";
  s += static_cast<char>(0x03);
  s += static_cast<char>(0xE8);
  s += static_cast<char>(0x00);
  s += static_cast<char>(0x01);
  auto p = parse_pgm(s, "w.pgm");
  ASSERT_TRUE(p.ok()) << p.error().c_str();
  EXPECT_EQ(p->pixels[0], 1000);
  EXPECT_EQ(p->pixels[1], 1);
}

TEST(Pgm, MalformedInputsAreErrors) {
  const char* bad[] = {"", "P6\n1 1\n255\n\x01", "P5\n0 1\n255\n", "P5\n2 2\n255\n\x01",
                       "P2\n2 1\n255\n1", "P2\n1 1\n10\n11", "P5\n1 1\n0\n\x00", "P5\n1 1\n255",
                       "P5\n99999999 1\n255\n"};
  for (const char* text : bad) {
    auto p = parse_pgm(text, "bad.pgm");
    ASSERT_FALSE(p.ok()) << text;
    EXPECT_NE(std::string(p.error().message()).find("bad.pgm"), std::string::npos);
  }
}

TEST(Occupancy, TrinaryThresholdsAreInclusive) {
  // p = (255 - v) / 255. occupied_thresh 0.6 is hit exactly by v = 102; free 0.2 by v = 204.
  PgmImage img;
  img.width = 5;
  img.height = 1;
  img.pixels = {102, 103, 204, 203, 0};
  MapYaml y = base_yaml();
  y.occupied_thresh = 0.6;
  y.free_thresh = 0.2;
  const OccupancyMap m = occupancy_from_image(img, y);
  EXPECT_EQ(m.at(0, 0), 100);  // p == occupied_thresh -> occupied
  EXPECT_EQ(m.at(1, 0), -1);
  EXPECT_EQ(m.at(2, 0), 0);  // p == free_thresh -> free
  EXPECT_EQ(m.at(3, 0), -1);
  EXPECT_EQ(m.at(4, 0), 100);
}

TEST(Occupancy, NegateInvertsBlackAndWhite) {
  PgmImage img;
  img.width = 2;
  img.height = 1;
  img.pixels = {0, 255};
  MapYaml y = base_yaml();
  y.negate = true;
  const OccupancyMap m = occupancy_from_image(img, y);
  EXPECT_EQ(m.at(0, 0), 0);
  EXPECT_EQ(m.at(1, 0), 100);
}

TEST(Occupancy, ScaleAndRawModes) {
  PgmImage img;
  img.width = 4;
  img.height = 1;
  img.pixels = {0, 255, 127, 50};
  MapYaml y = base_yaml();
  y.mode = MapMode::scale;
  OccupancyMap m = occupancy_from_image(img, y);
  EXPECT_EQ(m.at(0, 0), 100);
  EXPECT_EQ(m.at(1, 0), 0);
  const double p = (255.0 - 127.0) / 255.0;
  EXPECT_EQ(m.at(2, 0), static_cast<int>(std::rint((p - 0.25) / 0.4 * 100.0)));
  y.mode = MapMode::raw;
  m = occupancy_from_image(img, y);
  EXPECT_EQ(m.at(0, 0), 0);
  EXPECT_EQ(m.at(1, 0), -1);  // above 100: unknown
  EXPECT_EQ(m.at(2, 0), -1);
  EXPECT_EQ(m.at(3, 0), 50);
}

TEST(Occupancy, ImageIsFlippedSoRowZeroIsTheBottom) {
  PgmImage img;
  img.width = 1;
  img.height = 2;
  img.pixels = {0, 255};  // top black, bottom white
  const OccupancyMap m = occupancy_from_image(img, base_yaml());
  EXPECT_EQ(m.at(0, 0), 0);
  EXPECT_EQ(m.at(0, 1), 100);
}

TEST(OccupancyMap, OriginWithYaw) {
  const OccupancyMap m(10, 10, 0.5, 1.0, 2.0, M_PI / 2.0);
  double x = 0;
  double y = 0;
  m.cell_to_world(0, 0, x, y);
  EXPECT_NEAR(x, 1.0 - 0.25, 1e-12);  // grid +x is map +y
  EXPECT_NEAR(y, 2.0 + 0.25, 1e-12);
  int c = -1;
  int r = -1;
  ASSERT_TRUE(m.world_to_cell(0.1, 4.6, c, r));
  EXPECT_EQ(c, 5);
  EXPECT_EQ(r, 1);
  EXPECT_FALSE(m.world_to_cell(5.0, 2.0, c, r));
  EXPECT_FALSE(m.world_to_cell(1e30, -1e30, c, r));
}

TEST(LoadMap, ImagePathIsRelativeToTheYaml) {
  const auto dir = std::filesystem::temp_directory_path() / "sen3bot_map_test";
  std::filesystem::create_directories(dir / "img");
  {
    std::ofstream(dir / "img" / "m.pgm", std::ios::binary) << pgm_p5(2, 2, {0, 255, 255, 205});
    std::ofstream(dir / "m.yaml") << "image: img/m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nfree_thresh: 0.196\n";
    std::ofstream(dir / "missing.yaml") << "image: nope.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  }
  auto m = load_map((dir / "m.yaml").string());
  ASSERT_TRUE(m.ok()) << m.error().c_str();
  EXPECT_EQ(m->at(0, 1), 100);
  EXPECT_EQ(m->at(1, 0), -1);  // 205: gmapping's unknown grey
  auto missing = load_map((dir / "missing.yaml").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(std::string(missing.error().message()).find("missing.yaml: image: "), std::string::npos);
  EXPECT_FALSE(load_map((dir / "nothing.yaml").string()).ok());
}

TEST(LoadMap, ShippedLabMap) {
  auto m = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  ASSERT_TRUE(m.ok()) << m.error().c_str();
  EXPECT_EQ(m->width(), 160);
  EXPECT_EQ(m->height(), 190);
  EXPECT_DOUBLE_EQ(m->resolution_m(), 0.05);
  int c = 0;
  int r = 0;
  ASSERT_TRUE(m->world_to_cell(4.0, 7.0, c, r));
  EXPECT_EQ(m->at(c, r), 0);
  ASSERT_TRUE(m->world_to_cell(2.5, 2.0, c, r));
  EXPECT_EQ(m->at(c, r), 0);
  EXPECT_EQ(m->at(0, 0), 100);  // walls
}

}  // namespace
}  // namespace sen3bot::nav
