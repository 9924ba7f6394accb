// The live view's cost with one viewer at the default rates: the whole simulated firmware, its
// view row and server, and a viewer subscribed to every channel that reads everything, run in
// lockstep paced to the wall clock (so every channel goes out at its configured rate). It
// prints the CPU the view row and the server's thread use per second of the robot's time, as a
// share of one core (the same as per wall second where the machine keeps up).
//
//   sen3bot_view_load [--seconds S] [--runs N] [--config FILE]
//
// The target is 2 % of one core on the host (docs/view.md).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "ws_client.hpp"

using namespace sen3bot;

namespace {

struct Run {
  double row_percent = 0;     // the view row's CPU / wall time
  double server_percent = 0;  // the server thread's
  double messages_s = 0;
  double kib_s = 0;
  double row_mean_us = 0;
  double row_max_us = 0;
  double wall_per_sim = 0;  // 1: kept up with the wall clock
};

bool one_run(const std::string& config_path, double seconds, Run& out) {
  Result<sim::SimulatedRobot> loaded = sim::load_simulated_robot(config_path);
  if (!loaded) {
    std::fprintf(stderr, "view_load: %s\n", loaded.error().c_str());
    return false;
  }
  firmware::FirmwareConfig config = loaded->firmware;
  config.view.enabled = true;
  config.view.task.server.port = 0;
  config.tasks["view"].arena_bytes = 4 * 1024 * 1024;
  Result<std::unique_ptr<sim::SimBoard>> board = sim::SimBoard::create(loaded->world, true);
  if (!board) return false;
  std::FILE* sink = std::fopen("/dev/null", "w");
  firmware::Firmware fw(config, **board, sink);
  if (!(*board)->start() || !fw.init()) {
    std::fprintf(stderr, "view_load: the firmware did not start\n");
    return false;
  }
  view::Server& server = *fw.view()->server();
  auto viewer = std::make_unique<testing::WsClient>();
  if (viewer->connect("127.0.0.1", server.port()).find(" 101 ") == std::string::npos) return false;
  viewer->read();
  viewer->read();
  std::string sub = R"({"op":"subscribe","subscriptions":[)";
  for (std::size_t i = 0; i < server.board().channel_count(); ++i)
    sub += (i ? "," : "") + std::string(R"({"id":)") + std::to_string(i) + R"(,"channelId":)" + std::to_string(i) + "}";
  viewer->send_text(sub + "]}");
  std::atomic<bool> stop{false};
  std::thread reading([&] {
    while (!stop.load()) viewer->read(100);
  });
  hal::SimClock& clock = *(*board)->lockstep_clock();
  tasks::Scheduler& scheduler = fw.scheduler();
  std::size_t row = 0;
  while (row < scheduler.task_count() && scheduler.stats(row).name != "view") ++row;
  // Warm-up: the drivers connect, the first map goes out.
  auto paced = [&](double s) {
    const auto start = std::chrono::steady_clock::now();
    for (double t = 0; t < s; t += 0.05) {
      if (!scheduler.run_lockstep(clock, hal::millis(50))) return;
      std::this_thread::sleep_until(start + std::chrono::duration<double>(t + 0.05));
    }
  };
  paced(2.0);
  const tasks::TaskStats row_before = scheduler.stats(row);
  const std::int64_t server_before = server.thread_cpu_ns();
  const view::ServerCounters sent_before = server.counters();
  const auto wall_start = std::chrono::steady_clock::now();
  paced(seconds);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const tasks::TaskStats row_after = scheduler.stats(row);
  const std::int64_t server_after = server.thread_cpu_ns();
  const view::ServerCounters sent_after = server.counters();
  stop = true;
  reading.join();
  const double row_cpu_ns = static_cast<double>(row_after.cpu_mean_ns) * static_cast<double>(row_after.runs) -
                            static_cast<double>(row_before.cpu_mean_ns) * static_cast<double>(row_before.runs);
  // Per second of the robot's time: where the machine keeps up (the host) that is the wall
  // clock's; under an emulator that runs slower it is still the cost of one second of work.
  out.wall_per_sim = wall_s / seconds;
  out.row_percent = 100.0 * row_cpu_ns * 1e-9 / seconds;
  out.server_percent = 100.0 * static_cast<double>(server_after - server_before) * 1e-9 / seconds;
  out.messages_s = static_cast<double>(sent_after.sent - sent_before.sent) / seconds;
  out.kib_s = static_cast<double>(sent_after.sent_bytes - sent_before.sent_bytes) / 1024.0 / seconds;
  out.row_mean_us = static_cast<double>(row_after.cpu_mean_ns) / 1000.0;
  out.row_max_us = static_cast<double>(row_after.cpu_max_ns) / 1000.0;
  fw.shutdown();
  (*board)->stop();
  std::fclose(sink);
  return true;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10;
  int runs = 3;
  std::string config = SEN3BOT_SOURCE_DIR "/config/sim.yaml";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--seconds" && i + 1 < argc) seconds = std::atof(argv[++i]);
    else if (arg == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (arg == "--config" && i + 1 < argc) config = argv[++i];
    else {
      std::fprintf(stderr, "usage: sen3bot_view_load [--seconds S] [--runs N] [--config FILE]\n");
      return 2;
    }
  }
  std::vector<double> row, server, total, messages, kib, mean_us, max_us;
  for (int r = 0; r < runs; ++r) {
    Run run;
    if (!one_run(config, seconds, run)) return 1;
    std::printf("run %d: view row %.3f %%, server thread %.3f %%, %.0f messages/s, %.0f KiB/s, row step %.0f us mean %.0f us max"
                " (%.2f s of wall time per simulated second)\n",
                r + 1, run.row_percent, run.server_percent, run.messages_s, run.kib_s, run.row_mean_us, run.row_max_us,
                run.wall_per_sim);
    std::fflush(stdout);
    row.push_back(run.row_percent);
    server.push_back(run.server_percent);
    total.push_back(run.row_percent + run.server_percent);
    messages.push_back(run.messages_s);
    kib.push_back(run.kib_s);
    mean_us.push_back(run.row_mean_us);
    max_us.push_back(run.row_max_us);
  }
  std::printf("median of %d runs of %.0f s, one viewer, default rates: view row %.3f %% + server thread %.3f %% = %.3f %% of one core"
              " (target 2 %%); %.0f messages/s, %.0f KiB/s; row step mean %.0f us, max %.0f us\n",
              runs, seconds, median(row), median(server), median(total), median(messages), median(kib), median(mean_us),
              median(max_us));
  return median(total) <= 2.0 ? 0 : 1;
}
