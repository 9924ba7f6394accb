// The rows and commands whose libraries are heavy come from modules (row_module.hpp): they
// load once, a missing one is an error naming it, and the robot binary links none of those
// libraries.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "row_module.hpp"

namespace sen3bot::firmware {
namespace {

TEST(RowModule, EachModuleLoadsOnceWithItsOwnRowAndCommand) {
  Result<const RowModule*> camera = load_row_module("camera");
  ASSERT_TRUE(camera) << camera.error().c_str();
  EXPECT_NE((*camera)->camera, nullptr);
  EXPECT_NE((*camera)->command, nullptr);
  EXPECT_EQ((*camera)->vision, nullptr);
  EXPECT_EQ((*camera)->qr, nullptr);
  EXPECT_EQ((*camera)->recognition, nullptr);
  Result<const RowModule*> again = load_row_module("camera");
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *camera);
  Result<const RowModule*> sgp = load_row_module("sgp");
  ASSERT_TRUE(sgp) << sgp.error().c_str();
  EXPECT_EQ((*sgp)->camera, nullptr);
  EXPECT_NE((*sgp)->command, nullptr);
}

TEST(RowModule, AMissingModuleIsAnErrorNamingTheFileAndWhereItWasLookedFor) {
  Result<const RowModule*> missing = load_row_module("no-such-row");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code(), Errc::not_found);
  const std::string message = missing.error().c_str();
  EXPECT_NE(message.find("sen3bot-no-such-row.so not found"), std::string::npos) << message;
  EXPECT_NE(message.find("looked in"), std::string::npos) << message;
  char program[] = "x";
  char* argv[] = {program};
  std::FILE* err = std::tmpfile();
  ASSERT_NE(err, nullptr);
  EXPECT_EQ(row_module_command("no-such-row", "sen3bot thing", 1, argv, stdout, err), 2);
  std::fclose(err);
}

#ifdef SEN3BOT_ROBOT_BIN
// The budget: at most 60 shared libraries, and none of OpenCV, FFmpeg or curl.
TEST(RowModule, TheRobotBinaryLinksNoHeavyLibrary) {
  std::FILE* ldd = ::popen("ldd " SEN3BOT_ROBOT_BIN, "r");
  ASSERT_NE(ldd, nullptr);
  int libraries = 0;
  std::string heavy;
  char line[512];
  while (std::fgets(line, sizeof line, ldd) != nullptr) {
    ++libraries;
    const std::string text = line;
    for (const char* name : {"libopencv", "libavcodec", "libswscale", "libcurl", "libgdal", "libX11"})
      if (text.find(name) != std::string::npos) heavy += text;
  }
  EXPECT_EQ(::pclose(ldd), 0);
  EXPECT_GT(libraries, 3);
  EXPECT_LE(libraries, 60);
  EXPECT_TRUE(heavy.empty()) << heavy;
}
#endif

}  // namespace
}  // namespace sen3bot::firmware
