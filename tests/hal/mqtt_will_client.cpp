// A client that connects with a last will and then waits to be killed: the process that dies
// with its connection open in hal_mqtt_tests. A program of its own, started by the test (under
// the emulator in a cross build), rather than a fork of a test process that already runs the
// client library's threads: qemu-user cannot be trusted to fork those.
//   mqtt_will_client URL CLIENT_ID WILL_TOPIC WILL_PAYLOAD
// Prints "connected" once the broker has accepted it; exits 1 if it cannot open the client
// or is not connected within 20 s, 2 on a bad command line.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "sen3bot/hal/pubsub.hpp"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s URL CLIENT_ID WILL_TOPIC WILL_PAYLOAD\n", argv[0]);
    return 2;
  }
  sen3bot::hal::PubSubOptions o;
  o.url = argv[1];
  o.client_id = argv[2];
  o.will = sen3bot::hal::PubSubWill{argv[3], argv[4], 1, true};
  o.keepalive_s = 5;
  auto client = sen3bot::hal::open_mqtt(o);
  if (!client.ok()) {
    std::fprintf(stderr, "mqtt_will_client: %s\n", client.error().c_str());
    return 1;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while ((*client)->state() != sen3bot::hal::PubSubState::connected) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "mqtt_will_client: not connected within 20 s\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::printf("connected\n");
  std::fflush(stdout);
  for (;;) ::pause();
}
