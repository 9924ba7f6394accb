#include "cli_util.hpp"

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace sen3bot::firmware {

namespace {

std::atomic<int> g_stop_signal{0};
void on_stop_signal(int sig) { g_stop_signal.store(sig); }  // async-signal-safe: one atomic store

template <typename T>
bool parse_unsigned(std::string_view text, T& out, unsigned long long max) {
  const std::string s(text);
  if (s.empty() || s.front() == '-' || s.front() == '+') return false;
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(s.c_str(), &end, 0);
  if (errno != 0 || end == s.c_str() || *end != '\0' || v > max) return false;
  out = static_cast<T>(v);
  return true;
}

}  // namespace

bool parse_double(std::string_view text, double& out) {
  const std::string s(text);
  char* end = nullptr;
  errno = 0;
  out = std::strtod(s.c_str(), &end);
  return errno == 0 && end != s.c_str() && *end == '\0' && std::isfinite(out);
}

bool parse_u32(std::string_view text, std::uint32_t& out) { return parse_unsigned(text, out, 0xFFFFFFFFull); }
bool parse_u64(std::string_view text, std::uint64_t& out) { return parse_unsigned(text, out, ~0ull); }

bool parse_point_m(std::string_view text, msg::Point2D& out) {
  const std::size_t comma = text.find(',');
  double x = 0, y = 0;
  if (comma == std::string_view::npos || !parse_double(text.substr(0, comma), x) || !parse_double(text.substr(comma + 1), y))
    return false;
  out = {x, y};
  return true;
}

bool parse_lms200_variant(std::string_view text, lms200::Variant& out) {
  const std::size_t slash = text.find('/');
  if (slash == std::string_view::npos) return false;
  std::uint32_t angle = 0;
  double res_deg = 0;
  // 1 deg is the coarsest resolution, which also keeps the conversion in range.
  if (!parse_u32(text.substr(0, slash), angle) || angle > 0xFFFF || !parse_double(text.substr(slash + 1), res_deg) ||
      res_deg <= 0 || res_deg > 1)
    return false;
  const lms200::Variant v{static_cast<std::uint16_t>(angle), static_cast<std::uint16_t>(std::lround(res_deg * 100))};
  if (!lms200::valid_variant(v)) return false;
  out = v;
  return true;
}

int dispatch(int argc, char** argv, std::string_view program, const char* version, const char* usage,
             std::span<const Command> commands, std::FILE* out, std::FILE* err) {
  if (argc < 2) {
    std::fputs(usage, err);
    return 2;
  }
  const std::string_view word = argv[1];
  if (word == "--help" || word == "-h" || word == "help") {
    std::fputs(usage, out);
    return 0;
  }
  if (word == "version" || word == "--version") {
    std::fprintf(out, "%.*s %s\n", static_cast<int>(program.size()), program.data(), version);
    return 0;
  }
  for (const Command& c : commands) {
    if (c.word != word) continue;
    if (c.second.empty()) return c.run(argc - 2, argv + 2, out, err);
    if (argc >= 3 && c.second == argv[2]) return c.run(argc - 3, argv + 3, out, err);
  }
  std::fprintf(err, "%.*s: unknown command '%s'\n\n%s", static_cast<int>(program.size()), program.data(), argv[1], usage);
  return 2;
}

StopOnSignal::StopOnSignal() {
  g_stop_signal.store(0);
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &old_int_);
  sigaction(SIGTERM, &action, &old_term_);
}

StopOnSignal::~StopOnSignal() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
}

int StopOnSignal::requested() noexcept { return g_stop_signal.load(); }

bool read_secret(const std::string& path, std::string& out, std::string& problem) {
  std::ifstream in(path);
  if (!in) {
    problem = std::strerror(errno);
    return false;
  }
  std::getline(in, out);
  while (!out.empty() && (out.back() == '\r' || out.back() == ' ' || out.back() == '\t')) out.pop_back();
  if (out.empty()) {
    problem = "empty";
    return false;
  }
  return true;
}

std::int64_t clock_ns(clockid_t clock) noexcept {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

bool BrokerArgs::take(std::string_view arg, const std::string& value) {
  std::string* field = arg == "--broker"          ? &broker
                       : arg == "--username"      ? &username
                       : arg == "--password-file" ? &password_file
                       : arg == "--ca-file"       ? &ca_file
                       : arg == "--client-id"     ? &client_id
                                                  : nullptr;
  if (field != nullptr) *field = value;
  return field != nullptr;
}

Result<hal::PubSubOptions> BrokerArgs::options() const {
  if (!password_file.empty() && username.empty()) return Error(Errc::config, "--password-file needs --username");
  hal::PubSubOptions link;
  link.url = broker;
  link.client_id = client_id;
  link.username = username;
  link.ca_file = ca_file;
  if (!password_file.empty()) {
    std::string problem;
    if (!read_secret(password_file, link.password, problem))
      return Error::format(Errc::config, "--password-file %s: %s", password_file.c_str(), problem.c_str());
  }
  return link;
}

}  // namespace sen3bot::firmware
