// `sen3bot-centre formation`: the centre's formation controller as a host program on the site's
// broker (docs/formation.md). The decisions are formation::FormationService's; this is its
// real-time loop: the MQTT link, the example's task, the team, the clock, a step log and the
// stop signals. On the way out the team is told to stop at once rather than left to its hold.
#include <time.h>

#include <cerrno>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "centre_commands.hpp"
#include "cli_util.hpp"
#include "sen3bot/formation/examples.hpp"
#include "sen3bot/formation/service.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::centre {

using namespace firmware;  // the command-line helpers (cli_util.hpp)

namespace {

constexpr const char* kFormationUsage =
    "usage: sen3bot-centre formation --broker URL --example 1|2|3 --team SERIAL,SERIAL,...\n"
    "                                 [--username U --password-file F --ca-file F] [--client-id ID]\n"
    "                                 [--manufacturer M] [--interface NAME] [--v-max M_S] [--w-max RAD_S]\n"
    "                                 [--period S] [--hold S] [--pose-timeout S] [--log FILE.csv]\n"
    "                                 [--duration S]\n";

bool split_team(std::string_view text, std::vector<formation::TeamMember>& team, const std::string& manufacturer) {
  team.clear();
  while (!text.empty()) {
    const std::size_t comma = text.find(',');
    const std::string_view serial = text.substr(0, comma);
    if (serial.empty()) return false;
    team.push_back({manufacturer, std::string(serial)});
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
    if (text.empty()) return false;  // a trailing comma
  }
  return !team.empty();
}

// What the command line asks for.
struct FormationOptions {
  BrokerArgs mqtt;
  std::string team_text, log_path, manufacturer = "Sen3Bot", interface_name = "uagv";
  int example_number = 0;
  double duration_s = 0;
  double v_max = -1, w_max = -1;
  formation::FormationServiceConfig config;
};

// False, with the problem and the usage on err, for a command line that is not one.
bool parse_options(int argc, char** argv, FormationOptions& o, std::FILE* err) {
  o.mqtt.client_id = "ssc";
  formation::FormationServiceConfig& config = o.config;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot-centre formation: %s needs a value\n%s", argv[i], kFormationUsage);
      return false;
    }
    const std::string value = argv[++i];
    bool ok = !value.empty();
    double number = 0;
    if (o.mqtt.take(arg, value)) {
    } else if (arg == "--example") {
      ok = value == "1" || value == "2" || value == "3";
      if (ok) o.example_number = value[0] - '0';
    } else if (arg == "--team") {
      o.team_text = value;
    } else if (arg == "--manufacturer") {
      o.manufacturer = value;
    } else if (arg == "--interface") {
      o.interface_name = value;
    } else if (arg == "--v-max") {
      ok = parse_double(value, o.v_max) && o.v_max > 0;
    } else if (arg == "--w-max") {
      ok = parse_double(value, o.w_max) && o.w_max > 0;
    } else if (arg == "--period") {
      ok = parse_double(value, number) && number > 0;
      config.period_s = number;
    } else if (arg == "--hold") {
      ok = parse_double(value, number) && number > 0 && number <= 2.0;
      config.hold_s = number;
    } else if (arg == "--pose-timeout") {
      ok = parse_double(value, number) && number > 0;
      config.pose_timeout_s = number;
    } else if (arg == "--log") {
      o.log_path = value;
    } else if (arg == "--duration") {
      ok = parse_double(value, o.duration_s) && o.duration_s >= 0;
    } else {
      std::fprintf(err, "sen3bot-centre formation: unknown option '%s'\n%s", argv[i - 1], kFormationUsage);
      return false;
    }
    if (!ok) {
      std::fprintf(err, "sen3bot-centre formation: bad value '%s' for %s\n%s", argv[i], argv[i - 1], kFormationUsage);
      return false;
    }
  }
  const char* missing = o.mqtt.broker.empty()    ? "--broker"
                        : o.example_number == 0 ? "--example"
                        : o.team_text.empty()   ? "--team"
                                                : nullptr;
  if (missing != nullptr) {
    std::fprintf(err, "sen3bot-centre formation: %s is required\n%s", missing, kFormationUsage);
    return false;
  }
  return true;
}

// The example's controller with the limits asked for, and the team, which must be as large as
// the example's; false with the problem on err.
bool configure(FormationOptions& o, const formation::Example& example, std::FILE* err) {
  formation::FormationServiceConfig& config = o.config;
  config.interface_name = o.interface_name;
  config.controller = example.config;
  if (o.v_max > 0) config.controller.v_max_m_s = o.v_max;
  if (o.w_max > 0) config.controller.w_max_rad_s = o.w_max;
  if (!split_team(o.team_text, config.team, o.manufacturer)) {
    std::fprintf(err, "sen3bot-centre formation: --team: serial numbers separated by commas, got '%s'\n", o.team_text.c_str());
    return false;
  }
  if (config.team.size() != example.config.robots) {
    std::fprintf(err, "sen3bot-centre formation: --team: example %d drives %zu robots, got %zu serial numbers\n", o.example_number,
                 example.config.robots, config.team.size());
    return false;
  }
  return true;
}

// The service on its MQTT link; null, with the problem on err and the exit status in `status`,
// when either cannot be made.
std::unique_ptr<formation::FormationService> open_service(FormationOptions& o, std::FILE* err, int& status) {
  status = 2;
  formation::FormationServiceConfig& config = o.config;
  Result<hal::PubSubOptions> options = o.mqtt.options();
  if (!options) {
    std::fprintf(err, "sen3bot-centre formation: %s\n", options.error().c_str());
    return nullptr;
  }
  Result<std::vector<hal::PubSubSubscription>> subscriptions = formation::FormationService::subscriptions(config);
  if (!subscriptions) {
    std::fprintf(err, "sen3bot-centre formation: %s\n", subscriptions.error().c_str());
    return nullptr;
  }
  hal::PubSubOptions& link = *options;
  link.subscriptions = std::move(*subscriptions);
  // Ten robots' visualizations at 10 Hz are ten messages a step; room for a second's burst.
  link.inbound_slots = 128;
  link.outbound_slots = 64;
  config.max_payload = link.max_payload;
  Result<std::unique_ptr<hal::PubSub>> opened = hal::open_mqtt(link);
  if (!opened) {
    std::fprintf(err, "sen3bot-centre formation: --broker %s: %s\n", o.mqtt.broker.c_str(), opened.error().c_str());
    status = opened.error().code() == Errc::config ? 2 : 1;
    return nullptr;
  }
  Result<std::unique_ptr<formation::FormationService>> created = formation::FormationService::create(config, std::move(opened.value()));
  if (!created) {
    std::fprintf(err, "sen3bot-centre formation: %s\n", created.error().c_str());
    return nullptr;
  }
  return std::move(created.value());
}

// Steps the service until a stop signal or the end of `duration_s` (0: none), a line of the log
// for each step that did something; the operator hears of what changes the team's motion.
// Returns when the loop started (CLOCK_MONOTONIC).
std::int64_t run_steps(formation::FormationService& service, double period_s, double duration_s, std::FILE* log,
                       std::FILE* err) {
  const auto period = static_cast<std::int64_t>(period_s * 1e9 / 4.0);  // messages are taken between steps too
  const std::int64_t start = clock_ns(CLOCK_MONOTONIC);
  const std::int64_t end = duration_s > 0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : INT64_MAX;
  std::int64_t next = start;
  std::uint64_t switches_seen = 0, connects_seen = 0;
  bool stopped = false;  // the last step stopped the team
  while (StopOnSignal::requested() == 0) {
    const std::int64_t now = clock_ns(CLOCK_MONOTONIC);
    if (now >= end) break;
    const formation::StepOutcome outcome = service.step(now, clock_ns(CLOCK_REALTIME));
    if (outcome != formation::StepOutcome::idle && log != nullptr) {
      const formation::StepInfo& s = service.controller().last();
      std::fprintf(log, "%.3f,%s,%.4f,%.6g,%zu,%d,%.4f,%.4f\n", static_cast<double>(now - start) * 1e-9,
                   outcome == formation::StepOutcome::commanded ? "commanded" : "stopped", s.scale, s.lyapunov, s.gain_set,
                   s.switched ? 1 : 0, s.formation_error_m, s.min_barrier_m);
    }
    // The operator hears of what changes the team's motion, once each time.
    if (outcome == formation::StepOutcome::stopped && !stopped)
      std::fprintf(err, "sen3bot-centre formation: a robot's pose is missing or stale: the team is told to stop\n");
    if (outcome != formation::StepOutcome::idle) stopped = outcome == formation::StepOutcome::stopped;
    if (service.controller().switches() != switches_seen) {
      switches_seen = service.controller().switches();
      std::fprintf(err, "sen3bot-centre formation: gains switched to set %zu (switch %" PRIu64 ")\n", service.controller().gain_set(),
                   switches_seen);
    }
    const hal::PubSubStats stats = service.link().stats();
    if (stats.connects != connects_seen) {
      connects_seen = stats.connects;
      std::fprintf(err, "sen3bot-centre formation: connected to the broker (connection %" PRIu64 ")\n", connects_seen);
    }
    next += period;
    if (clock_ns(CLOCK_MONOTONIC) > next) {
      next = clock_ns(CLOCK_MONOTONIC);
      continue;
    }
    const timespec wake{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR && StopOnSignal::requested() == 0) {
    }
  }
  return start;
}

// The run's counters as one JSON line on out.
void print_summary(formation::FormationService& service, std::int64_t start, std::FILE* out) {
  const formation::FormationCounters& c = service.counters();
  const hal::PubSubStats link_stats = service.link().stats();
  const int signal = StopOnSignal::requested();
  json::FileSink sink(out);
  json::Writer(sink)
      .begin_object()
      .member("stopped_by", signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : "duration")
      .key("run_s").fixed_or_null(static_cast<double>(clock_ns(CLOCK_MONOTONIC) - start) * 1e-9, 1)
      .member_uint64("poses", c.poses)
      .member_uint64("rejected", c.rejected)
      .member_uint64("controller_steps", c.controller_steps)
      .member_uint64("stale_steps", c.stale_steps)
      .member_uint64("commands_sent", c.commands_sent)
      .member_uint64("switches", service.controller().switches())
      .key("formation_error_m").fixed_or_null(service.controller().last().formation_error_m, 4)
      .member_uint64("connects", link_stats.connects)
      .member_uint64("publish_dropped", link_stats.publish_dropped)
      .end_object();
  std::fputc('\n', out);
  std::fflush(out);
}

}  // namespace

int formation_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  FormationOptions o;
  if (!parse_options(argc, argv, o, err)) return 2;
  const formation::Example example = formation::example(o.example_number);
  if (!configure(o, example, err)) return 2;
  int status = 0;
  std::unique_ptr<formation::FormationService> created = open_service(o, err, status);
  if (!created) return status;
  formation::FormationService& service = *created;

  std::FILE* log = nullptr;
  if (!o.log_path.empty()) {
    log = std::fopen(o.log_path.c_str(), "w");
    if (log == nullptr) {
      std::fprintf(err, "sen3bot-centre formation: --log %s: %s\n", o.log_path.c_str(), std::strerror(errno));
      return 2;
    }
    std::fprintf(log, "t_s,outcome,scale,lyapunov,gain_set,switched,formation_error_m,min_barrier_m\n");
  }
  std::fprintf(err, "sen3bot-centre formation: example %d (%s), %zu robots, on %s as %s\n", o.example_number, example.title,
               o.config.team.size(), o.mqtt.broker.c_str(), o.mqtt.client_id.c_str());

  const StopOnSignal stop;
  const std::int64_t start = run_steps(service, o.config.period_s, o.duration_s, log, err);
  service.stop_team(clock_ns(CLOCK_REALTIME));
  print_summary(service, start, out);
  service.close(1.0);  // the stop goes out, then a clean disconnect
  created.reset();
  if (log != nullptr) std::fclose(log);
  return 0;
}

}  // namespace sen3bot::centre
