// `sen3bot-sim agv`: one simulated plant AGV (SimAgv) in real time on a real broker, for tests
// and demonstrations of the centre: it takes VDA 5050 orders and instant actions from whoever is
// master control, reports its state, and obeys the advisory when the broker lets it read it.
// No people are simulated: its own scanner sees nobody.
#include <time.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/sim/agv.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

namespace {

constexpr const char* kAgvUsage =
    "usage: sen3bot-sim agv --broker URL --serial S [--manufacturer M] [--map-id ID] [--speed M_S]\n"
    "                       [--x X --y Y --theta RAD] [--duration S]\n"
    "                       [--username U --password-file F --ca-file F] [--client-id ID]\n";

constexpr double kStepS = 0.05;  // 20 Hz

}  // namespace

int agv_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  SimAgvConfig config;
  firmware::BrokerArgs args;
  bool serial_given = false;
  double duration_s = 0;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot-sim agv: %s needs a value\n%s", argv[i], kAgvUsage);
      return 2;
    }
    const std::string value = argv[++i];
    bool ok = !value.empty();
    if (args.take(arg, value)) {
    } else if (arg == "--serial") {
      config.serial_number = value;
      serial_given = true;
    } else if (arg == "--manufacturer") {
      config.manufacturer = value;
    } else if (arg == "--map-id") {
      config.map_id = value;
    } else if (arg == "--speed") {
      ok = firmware::parse_double(value, config.speed_m_s) && config.speed_m_s > 0 && config.speed_m_s <= 10;
    } else if (arg == "--x") {
      ok = firmware::parse_double(value, config.x);
    } else if (arg == "--y") {
      ok = firmware::parse_double(value, config.y);
    } else if (arg == "--theta") {
      ok = firmware::parse_double(value, config.theta);
    } else if (arg == "--duration") {
      ok = firmware::parse_double(value, duration_s) && duration_s >= 0;
    } else {
      std::fprintf(err, "sen3bot-sim agv: unknown option '%s'\n%s", argv[i - 1], kAgvUsage);
      return 2;
    }
    if (!ok) {
      std::fprintf(err, "sen3bot-sim agv: bad value '%s' for %s\n%s", argv[i], argv[i - 1], kAgvUsage);
      return 2;
    }
  }
  // The AGV answers to the serial number its plant's master control orders it by: no default.
  if (args.broker.empty() || !serial_given) {
    std::fprintf(err, "sen3bot-sim agv: %s is required\n%s", args.broker.empty() ? "--broker" : "--serial", kAgvUsage);
    return 2;
  }
  if (args.client_id.empty()) args.client_id = config.serial_number;
  Result<hal::PubSubOptions> options = args.options();
  if (!options) {
    std::fprintf(err, "sen3bot-sim agv: %s\n", options.error().c_str());
    return 2;
  }
  hal::PubSubOptions& link = *options;
  link.subscriptions = SimAgv::subscriptions(config);
  // The broker's last will tells the centre the AGV is gone (VDA 5050 section 6.14).
  const std::string connection_topic =
      config.interface_name + "/v2/" + config.manufacturer + "/" + config.serial_number + "/connection";
  auto connection_text = [&](vda5050::ConnectionState state) {
    vda5050::Connection c;
    c.header.timestamp = vda5050::iso8601(firmware::clock_ns(CLOCK_REALTIME));
    (void)c.header.version.assign(vda5050::to_string(config.version));
    (void)c.header.manufacturer.assign(config.manufacturer);
    (void)c.header.serial_number.assign(config.serial_number);
    c.state = state;
    std::array<char, 1024> buffer{};
    auto text = vda5050::encode_connection(c, config.version, buffer);
    return text ? std::string(*text) : std::string();
  };
  link.will = hal::PubSubWill{connection_topic, connection_text(vda5050::ConnectionState::connection_broken), 1, true};
  Result<std::unique_ptr<hal::PubSub>> opened = hal::open_mqtt(link);
  if (!opened) {
    std::fprintf(err, "sen3bot-sim agv: --broker %s: %s\n", args.broker.c_str(), opened.error().c_str());
    return opened.error().code() == Errc::config ? 2 : 1;
  }
  hal::PubSub& link_handle = *opened.value();  // the AGV owns it; kept for the goodbye below
  SimAgv agv(config, std::move(opened.value()));

  const firmware::StopOnSignal stop;
  const auto period = static_cast<std::int64_t>(kStepS * 1e9);
  const std::int64_t start = firmware::clock_ns(CLOCK_MONOTONIC);
  const std::int64_t end = duration_s > 0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : INT64_MAX;
  std::int64_t next = start;
  std::int64_t last = start;
  while (firmware::StopOnSignal::requested() == 0) {
    const std::int64_t now = firmware::clock_ns(CLOCK_MONOTONIC);
    if (now >= end) break;
    // The real time since the last step, so a late step still moves the AGV the right distance.
    const double dt = static_cast<double>(now - last) * 1e-9;
    last = now;
    agv.step(now - start, firmware::clock_ns(CLOCK_REALTIME), dt);
    next += period;
    if (firmware::clock_ns(CLOCK_MONOTONIC) > next) {
      next = firmware::clock_ns(CLOCK_MONOTONIC);
      continue;
    }
    const timespec wake{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR && firmware::StopOnSignal::requested() == 0) {
    }
  }
  // A clean stop says OFFLINE, retained, and waits for the broker to take it.
  const std::string offline = connection_text(vda5050::ConnectionState::offline);
  (void)link_handle.publish(connection_topic, {reinterpret_cast<const std::uint8_t*>(offline.data()), offline.size()}, 1, true);
  link_handle.close(1.0);
  json::FileSink sink(out);
  json::Writer(sink)
      .begin_object()
      .member("serial", config.serial_number)
      .key("x").fixed_or_null(agv.x(), 3)
      .key("y").fixed_or_null(agv.y(), 3)
      .key("theta").fixed_or_null(agv.theta(), 3)
      .member_bool("paused", agv.vehicle().paused())
      .member("advice", vda5050::to_string(agv.advice()))
      .member_uint64("advisories", agv.advisories())
      .end_object();
  std::fputc('\n', out);
  std::fflush(out);
  return 0;
}

}  // namespace sen3bot::sim
