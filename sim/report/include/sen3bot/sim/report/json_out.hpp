#pragma once
// The pieces of JSON the simulator's reports print by hand (report.json of sim, experiment
// crowd and operations): a quoted string and a number that is null when not finite.
#include <cstdio>
#include <string>
#include <string_view>

namespace sen3bot::sim::report {

// `s` as a JSON string: quotes, backslashes escaped, control characters as \u00XX.
[[nodiscard]] std::string json_quoted(std::string_view s);
void write_json_string(std::FILE* f, std::string_view s);
// `v` with the printf format, or null when it is not finite (JSON has no inf or NaN).
void write_json_number(std::FILE* f, double v, const char* format = "%.4f");

}  // namespace sen3bot::sim::report
