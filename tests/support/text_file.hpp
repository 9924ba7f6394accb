#pragma once
// A whole file as a string, for tests that read what a command wrote (empty when unreadable),
// and the numbers in a report's JSON.
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace sen3bot::testing {

inline std::string read_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

// The number after the n-th (from 0) `"key": ` in json; -1e9 when there is none.
inline double json_number(const std::string& json, const std::string& key, int n = 0) {
  std::size_t at = std::string::npos;
  for (int i = 0; i <= n; ++i) {
    at = json.find("\"" + key + "\": ", at == std::string::npos ? 0 : at + 1);
    if (at == std::string::npos) return -1e9;
  }
  return std::strtod(json.c_str() + at + key.size() + 4, nullptr);
}

}  // namespace sen3bot::testing
