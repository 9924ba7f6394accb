// The paths file (JSON lines): round trips, and every bad line refused with its number.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sen3bot/cobot/path_file.hpp"

namespace sen3bot::cobot {
namespace {

TEST(PathFile, RoundTrip) {
  PathRecord r{"w \"7\"", "kitting", {1.6f, 7.05f, 1.7f, 7.0123f, -0.25f, 9.4f}};
  const std::string line = path_line(r);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  Result<PathRecord> back = parse_path_line(line);
  ASSERT_TRUE(back.ok()) << back.error().c_str() << " in " << line;
  EXPECT_EQ(back->name, r.name);
  EXPECT_EQ(back->operation, r.operation);
  ASSERT_EQ(back->points(), 3u);
  for (std::size_t i = 0; i < r.xy.size(); ++i) EXPECT_NEAR(back->xy[i], r.xy[i], 0.0006f);
  // Without a truth the member is left out.
  const std::string unlabelled = path_line({"", "", {1.0f, 2.0f}});
  EXPECT_EQ(unlabelled.find("operation"), std::string::npos) << unlabelled;
  ASSERT_TRUE(parse_path_line(unlabelled).ok());
}

TEST(PathFile, ManyLinesWithBlanks) {
  const std::string text =
      "{\"name\": \"a\", \"operation\": \"kitting\", \"points\": [[1, 2], [3, 4]]}\n"
      "\n"
      "   \r\n"
      "{\"points\": [], \"name\": \"b\"}\r\n"
      "{\"name\": \"c\", \"points\": [[0.5, 0.25]]}";  // no final newline
  Result<std::vector<PathRecord>> paths = parse_paths(text, "p.jsonl");
  ASSERT_TRUE(paths.ok()) << paths.error().c_str();
  ASSERT_EQ(paths->size(), 3u);
  EXPECT_EQ((*paths)[0].operation, "kitting");
  EXPECT_EQ((*paths)[0].xy, (std::vector<float>{1, 2, 3, 4}));
  EXPECT_EQ((*paths)[1].points(), 0u);
  EXPECT_EQ((*paths)[2].name, "c");
}

TEST(PathFile, BadLinesNameTheirNumber) {
  struct Case {
    std::string line;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"{\"points\": [[1, 2]]", ""},                                   // not JSON
      {"[[1, 2]]", "expected a JSON object"},
      {"{\"name\": \"x\"}", "no \"points\""},
      {"{\"points\": [[1, 2]], \"pionts\": []}", "unknown member"},
      {"{\"points\": [[1, 2, 3]]}", "expected [x, y]"},
      {"{\"points\": [1, 2]}", "expected [x, y]"},
      {"{\"points\": {\"x\": 1}}", "expected an array of [x, y]"},
      {"{\"points\": [[\"1\", 2]]}", "expected a coordinate in metres"},
      {"{\"points\": [[1e300, 2]]}", "expected a coordinate in metres"},
      {"{\"name\": 5, \"points\": []}", "\"name\": expected a string"},
      {"{\"operation\": [], \"points\": []}", "\"operation\": expected a string"},
      {"{\"name\": \"" + std::string(300, 'n') + "\", \"points\": []}", "longer than 256 bytes"},
  };
  for (const Case& c : cases) {
    const std::string text = "{\"points\": [[0, 0]]}\n\n" + c.line + "\n{\"points\": []}\n";
    Result<std::vector<PathRecord>> paths = parse_paths(text, "p.jsonl");
    ASSERT_FALSE(paths.ok()) << "accepted: " << c.line;
    const std::string error = paths.error().c_str();
    EXPECT_EQ(error.rfind("p.jsonl: line 3: ", 0), 0u) << error;
    EXPECT_NE(error.find(c.message), std::string::npos) << "expected '" << c.message << "' in: " << error;
  }
}

TEST(PathFile, PointLimit) {
  auto line_of = [](std::size_t points) {
    std::string s = "{\"points\": [";
    for (std::size_t i = 0; i < points; ++i) s += (i ? ",[1,2]" : "[1,2]");
    return s + "]}";
  };
  Result<PathRecord> full = parse_path_line(line_of(1024));
  ASSERT_TRUE(full.ok()) << full.error().c_str();
  EXPECT_EQ(full->points(), 1024u);
  Result<PathRecord> over = parse_path_line(line_of(1025));
  ASSERT_FALSE(over.ok());
  EXPECT_NE(std::string(over.error().c_str()).find("more than 1024 points"), std::string::npos) << over.error().c_str();
}

TEST(PathFile, MissingFile) {
  Result<std::vector<PathRecord>> paths = load_paths("/nonexistent/paths.jsonl");
  ASSERT_FALSE(paths.ok());
  EXPECT_EQ(paths.error().code(), Errc::not_found);
}

}  // namespace
}  // namespace sen3bot::cobot
