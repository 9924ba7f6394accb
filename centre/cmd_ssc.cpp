// `sen3bot-centre ssc`: the Sensors Synergy Centre as a host program on the site's broker. The
// decisions are ssc::Service's; this is only its real-time loop: the MQTT link, the site file,
// the event log, the clock and the stop signals.
#include <time.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "centre_commands.hpp"
#include "cli_util.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/ssc/service.hpp"

namespace sen3bot::centre {

using namespace firmware;  // the command-line helpers (cli_util.hpp)

namespace {

constexpr const char* kSscUsage =
    "usage: sen3bot-centre ssc --broker URL --site SITE.yaml [--username U --password-file F --ca-file F]\n"
    "                           [--event-log FILE] [--duration S] [--client-id ID]\n";

}  // namespace

int ssc_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  BrokerArgs args;
  args.client_id = "ssc";
  std::string site_path, event_log_path;
  double duration_s = 0;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot-centre ssc: %s needs a value\n%s", argv[i], kSscUsage);
      return 2;
    }
    const std::string value = argv[++i];
    bool ok = !value.empty();
    if (args.take(arg, value)) {
    } else if (arg == "--site") {
      site_path = value;
    } else if (arg == "--event-log") {
      event_log_path = value;
    } else if (arg == "--duration") {
      ok = parse_double(value, duration_s) && duration_s >= 0;
    } else {
      std::fprintf(err, "sen3bot-centre ssc: unknown option '%s'\n%s", argv[i - 1], kSscUsage);
      return 2;
    }
    if (!ok) {
      std::fprintf(err, "sen3bot-centre ssc: bad value '%s' for %s\n%s", argv[i], argv[i - 1], kSscUsage);
      return 2;
    }
  }
  if (args.broker.empty() || site_path.empty()) {
    std::fprintf(err, "sen3bot-centre ssc: %s is required\n%s", args.broker.empty() ? "--broker" : "--site", kSscUsage);
    return 2;
  }

  Result<ssc::SiteFile> site = ssc::load_site(site_path);
  if (!site) {
    std::fprintf(err, "sen3bot-centre ssc: %s\n", site.error().c_str());
    return 2;
  }

  Result<hal::PubSubOptions> options = args.options();
  if (!options) {
    std::fprintf(err, "sen3bot-centre ssc: %s\n", options.error().c_str());
    return 2;
  }
  hal::PubSubOptions& link = *options;
  link.subscriptions = ssc::Service::subscriptions(site->service);
  // What arrives between two steps: 50 robots at 10 people reports a second and 150 vehicles'
  // states at 1 Hz are about 35 messages a step at 20 Hz; room for a burst of 512.
  link.inbound_slots = 512;
  link.outbound_slots = 256;
  Result<std::unique_ptr<hal::PubSub>> opened = hal::open_mqtt(link);
  if (!opened) {
    std::fprintf(err, "sen3bot-centre ssc: --broker %s: %s\n", args.broker.c_str(), opened.error().c_str());
    return opened.error().code() == Errc::config ? 2 : 1;
  }

  std::FILE* event_log = nullptr;
  if (!event_log_path.empty()) {
    // Appended: a restarted centre's decisions follow the earlier ones' in one file.
    event_log = std::fopen(event_log_path.c_str(), "a");
    if (event_log == nullptr) {
      std::fprintf(err, "sen3bot-centre ssc: --event-log %s: %s\n", event_log_path.c_str(), std::strerror(errno));
      return 2;
    }
  }

  Result<std::unique_ptr<ssc::Service>> created = ssc::Service::create(*site, std::move(opened.value()), event_log);
  if (!created) {
    std::fprintf(err, "sen3bot-centre ssc: %s: %s\n", site_path.c_str(), created.error().c_str());
    if (event_log != nullptr) std::fclose(event_log);
    return 2;
  }
  ssc::Service& service = **created;
  std::fprintf(err, "sen3bot-centre ssc: site %s (%zu robots, %zu areas) on %s as %s\n", site_path.c_str(),
               site->robot_serials.size(), site->area_names.size(), args.broker.c_str(), args.client_id.c_str());

  const StopOnSignal stop;
  const std::int64_t period = static_cast<std::int64_t>(site->service.step_period_s * 1e9);
  const std::int64_t start = clock_ns(CLOCK_MONOTONIC);
  const std::int64_t end = duration_s > 0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : INT64_MAX;
  std::int64_t next = start;
  std::uint64_t steps = 0, overruns = 0;
  std::uint64_t refusals_seen = 0;
  std::uint64_t connects_seen = 0;
  while (StopOnSignal::requested() == 0) {
    const std::int64_t now = clock_ns(CLOCK_MONOTONIC);
    if (now >= end) break;
    service.step(now, clock_ns(CLOCK_REALTIME));
    ++steps;

    // The link connects and reconnects by itself; the operator hears about it once each time.
    const hal::PubSubStats stats = service.link().stats();
    if (stats.connections_refused != refusals_seen) {
      refusals_seen = stats.connections_refused;
      std::fprintf(err, "sen3bot-centre ssc: the broker refused the connection (credentials or client id); retrying\n");
    }
    if (stats.connects != connects_seen) {
      connects_seen = stats.connects;
      std::fprintf(err, "sen3bot-centre ssc: connected to the broker (connection %llu)\n", static_cast<unsigned long long>(connects_seen));
    }

    next += period;
    if (clock_ns(CLOCK_MONOTONIC) > next) {
      // Late: skip the missed steps rather than running them back to back.
      ++overruns;
      next = clock_ns(CLOCK_MONOTONIC);
      continue;
    }
    const timespec wake{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR && StopOnSignal::requested() == 0) {
    }
  }

  const ssc::ServiceCounters& c = service.counters();
  const hal::PubSubStats link_stats = service.link().stats();
  const int signal = StopOnSignal::requested();
  json::FileSink sink(out);
  json::Writer(sink)
      .begin_object()
      .member("stopped_by", signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : "duration")
      .key("run_s").fixed_or_null(static_cast<double>(clock_ns(CLOCK_MONOTONIC) - start) * 1e-9, 1)
      .member_uint64("steps", steps)
      .member_uint64("overruns", overruns)
      .member_uint64("states", c.states)
      .member_uint64("people_reports", c.people_reports)
      .member_uint64("rejected", c.rejected)
      .member_uint64("orders_sent", c.orders_sent)
      .member_uint64("cancels_sent", c.cancels_sent)
      .member_uint64("advisories_sent", c.advisories_sent)
      .member_uint64("pauses_sent", c.pauses_sent)
      .member_uint64("unknown_agvs", c.unknown_agvs)
      .member_uint64("connects", link_stats.connects)
      .member_uint64("connection_losses", link_stats.connection_losses)
      .member_uint64("receive_dropped", link_stats.receive_dropped)
      .member_uint64("publish_dropped", link_stats.publish_dropped)
      .end_object();
  std::fputc('\n', out);
  std::fflush(out);
  service.close(1.0);  // what the last step queued goes out, then a clean disconnect
  created.value().reset();
  if (event_log != nullptr) std::fclose(event_log);
  return 0;
}

}  // namespace sen3bot::centre
