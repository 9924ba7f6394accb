#pragma once
// A whole file as a string, for tests that read what a command wrote (empty when unreadable).
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

}  // namespace sen3bot::testing
