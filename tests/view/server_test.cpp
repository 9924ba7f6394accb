// The live view's server without the firmware: the channel board's hand-off, the protocol's
// client operations, and the server over real sockets (the page, the upgrade, security, client
// messages, a stalled client).
#include <gtest/gtest.h>
#include <ifaddrs.h>
#include <net/if.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <memory_resource>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/view/channel_board.hpp"
#include "sen3bot/view/server.hpp"
#include "sen3bot/view/session.hpp"
#include "ws_client.hpp"

namespace sen3bot::view {
namespace {

using testing::WsClient;

std::pmr::memory_resource& heap() { return *std::pmr::new_delete_resource(); }

void put(ChannelBoard& board, std::size_t ch, std::string_view text, hal::Nanos stamp) {
  std::span<char> space = board.space(ch);
  ASSERT_GE(space.size(), text.size());
  std::memcpy(space.data(), text.data(), text.size());
  board.commit(ch, text.size(), stamp);
}

std::string_view text_of(const Publication& p, std::size_t i) { return {p.payload(i).data(), p.payload(i).size()}; }

// --- The board ---------------------------------------------------------------------------

TEST(ChannelBoard, TheConsumerGetsTheNewestPublishAndKeepsItUntilTheNextTake) {
  const ChannelSpec specs[] = {{"/a", Schema::mission, 64}, {"/b", Schema::task_stats, 64}};
  auto board = ChannelBoard::create(specs, 32, heap());
  ASSERT_TRUE(board);
  ChannelBoard& b = **board;
  EXPECT_EQ(b.take(0).seq, 0u);  // nothing yet
  put(b, 0, "one", 1);
  b.publish(0);
  put(b, 0, "two", 2);
  b.publish(0);
  const Publication& newest = b.take(0);
  EXPECT_EQ(newest.seq, 2u);  // "one" was superseded before anyone took it
  ASSERT_EQ(newest.record_count, 1u);
  EXPECT_EQ(text_of(newest, 0), "two");
  EXPECT_EQ(newest.records[0].stamp_ns, 2);
  put(b, 0, "three", 3);  // being built: the consumer's buffer is untouched
  EXPECT_EQ(text_of(b.take(0), 0), "two");
  b.publish(0);
  EXPECT_EQ(text_of(b.take(0), 0), "three");
  EXPECT_EQ(b.take(1).seq, 0u);  // channels are independent
  b.publish(1);                  // an empty publish is ignored
  EXPECT_EQ(b.take(1).seq, 0u);
  // Every payload keeps its headroom for the frame header in front of it.
  const Publication& p = b.take(0);
  EXPECT_GE(p.records[0].offset, 32u);
}

TEST(ChannelBoard, OnePublishHoldsSeveralMessagesAndRefusesWhatDoesNotFit) {
  const ChannelSpec specs[] = {{"/tf", Schema::frame_transform, 40}};
  auto board = ChannelBoard::create(specs, 16, heap());
  ASSERT_TRUE(board);
  ChannelBoard& b = **board;
  put(b, 0, "first", 1);
  put(b, 0, "second", 2);
  put(b, 0, "third", 3);
  b.publish(0);
  const Publication& p = b.take(0);
  ASSERT_EQ(p.record_count, 3u);
  EXPECT_EQ(text_of(p, 0), "first");
  EXPECT_EQ(text_of(p, 1), "second");
  EXPECT_EQ(text_of(p, 2), "third");
  for (std::size_t i = 0; i < kMaxRecords; ++i) b.commit(0, 1, 0);
  EXPECT_TRUE(b.space(0).empty());  // kMaxRecords in
  b.discard(0);
  EXPECT_FALSE(b.space(0).empty());
  b.commit(0, b.space(0).size() + 1, 0);  // larger than the space: ignored
  b.publish(0);
  EXPECT_EQ(b.take(0).seq, 1u);
}

TEST(ChannelBoard, RefusesNoChannelsTooManyAndEmptyOnes) {
  EXPECT_FALSE(ChannelBoard::create({}, 16, heap()));
  std::vector<ChannelSpec> many(kMaxChannels + 1, ChannelSpec{"/x", Schema::mission, 8});
  EXPECT_FALSE(ChannelBoard::create(many, 16, heap()));
  const ChannelSpec empty[] = {{"/x", Schema::mission, 0}};
  EXPECT_FALSE(ChannelBoard::create(empty, 16, heap()));
}

TEST(ChannelBoard, AProducerAndAConsumerOnTwoThreadsNeverSeeATornMessage) {
  const ChannelSpec specs[] = {{"/a", Schema::mission, 4096}};
  auto board = ChannelBoard::create(specs, 32, heap());
  ASSERT_TRUE(board);
  ChannelBoard& b = **board;
  // The producer keeps publishing until the consumer has seen enough distinct
  // messages: how the two threads interleave is the scheduler's choice, so a
  // fixed count could end before the consumer ever ran.
  constexpr std::uint64_t kMinPublishes = 200'000, kMinTakes = 200;
  std::atomic<bool> seen_enough{false};
  std::atomic<std::uint32_t> published{0};
  std::thread producer([&] {
    std::uint32_t i = 0;
    while (i < kMinPublishes || !seen_enough.load(std::memory_order_relaxed)) {
      ++i;
      std::span<char> space = b.space(0);
      const std::size_t n = 64 + i % 2000;
      std::memset(space.data(), static_cast<int>(i & 0xff), n);
      b.commit(0, n, i);
      b.publish(0);
    }
    published = i;
  });
  std::uint64_t last = 0, torn = 0, backwards = 0, takes = 0;
  while (published.load() == 0) {
    const Publication& p = b.take(0);
    if (p.seq == 0 || p.seq == last) continue;
    ++takes;
    if (takes == kMinTakes) seen_enough = true;
    if (p.seq < last) ++backwards;
    last = p.seq;
    const auto i = static_cast<std::uint32_t>(p.records[0].stamp_ns);
    const std::span<char> payload = p.payload(0);
    if (payload.size() != 64 + i % 2000) ++torn;
    for (char c : payload) torn += static_cast<unsigned char>(c) != (i & 0xff);
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_GE(takes, kMinTakes);
  EXPECT_EQ(b.take(0).seq, published.load());
}

TEST(ChannelBoard, PublishingAllocatesNothing) {
  const ChannelSpec specs[] = {{"/a", Schema::mission, 256}};
  auto board = ChannelBoard::create(specs, 32, heap());
  ASSERT_TRUE(board);
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    put(**board, 0, "{\"x\":1}", i);
    (*board)->publish(0);
    (void)(*board)->take(0);
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
}

// --- The protocol ------------------------------------------------------------------------

std::string reply_of(Session& s) {
  if (!s.has_reply()) return {};
  std::string r(s.reply());
  s.pop_reply();
  return r;
}

TEST(Session, SubscribeAndUnsubscribeChangeOnlyWhatTheyName) {
  auto s = std::make_unique<Session>(3);
  s->on_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":0},{"id":9,"channelId":2}]})");
  EXPECT_FALSE(s->has_reply());
  EXPECT_EQ(s->subscription(0), 7u);
  EXPECT_EQ(s->subscription(1), Session::kNone);
  EXPECT_EQ(s->subscription(2), 9u);
  EXPECT_EQ(s->subscribed_channels(), 2u);
  s->on_text(R"({"op":"unsubscribe","subscriptionIds":[7]})");
  EXPECT_FALSE(s->has_reply());
  EXPECT_EQ(s->subscription(0), Session::kNone);
  EXPECT_EQ(s->subscription(2), 9u);
}

TEST(Session, EveryOtherOperationIsRefusedWithAStatusAndChangesNothing) {
  auto s = std::make_unique<Session>(2);
  s->on_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":0}]})");
  struct Case {
    const char* text;
    int level;
    const char* says;
  };
  const Case cases[] = {
      {R"({"op":"advertise","channels":[{"id":1,"topic":"/cmd_vel","encoding":"json","schemaName":"x"}]})", 2, "read-only"},
      {R"({"op":"unadvertise","channelIds":[1]})", 2, "read-only"},
      {R"({"op":"getParameters","parameterNames":[]})", 2, "read-only"},
      {R"({"op":"setParameters","parameters":[{"name":"max_v","value":9}]})", 2, "read-only"},
      {R"({"op":"subscribeParameterUpdates","parameterNames":["a"]})", 2, "read-only"},
      {R"({"op":"subscribeConnectionGraph"})", 2, "read-only"},
      {R"({"op":"fetchAsset","uri":"file:///etc/shadow","requestId":1})", 2, "read-only"},
      {R"({"op":"frobnicate"})", 2, "unknown op"},
      {R"({"op":)", 2, "malformed"},
      {R"([1,2,3])", 2, "JSON object"},
      {R"({"op":42})", 2, "JSON object"},
      {R"({"op":"subscribe","subscriptions":{}})", 2, "must be an array"},
      {R"({"op":"subscribe","subscriptions":[{"id":2,"channelId":5}]})", 1, "not advertised"},
      {R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})", 2, "already in use"},
      {R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})", 2, "integer"},
      {R"({"op":"unsubscribe","subscriptionIds":[99]})", 1, "no subscription"},
  };
  for (const Case& c : cases) {
    s->on_text(c.text);
    const std::string reply = reply_of(*s);
    json::StaticDocument<64> doc;
    ASSERT_TRUE(doc.parse(reply)) << c.text << " -> " << reply;
    EXPECT_TRUE(doc.root().find("op").string_equals("status")) << reply;
    EXPECT_EQ(*doc.root().find("level").uint32(), static_cast<std::uint32_t>(c.level)) << c.text;
    EXPECT_NE(reply.find(c.says), std::string::npos) << c.text << " -> " << reply;
    EXPECT_EQ(s->subscription(0), 1u) << c.text;
    EXPECT_EQ(s->subscription(1), Session::kNone) << c.text;
  }
  s->on_binary(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>("\x01\x00\x00\x00\x00{}"), 7));
  EXPECT_NE(reply_of(*s).find("binary"), std::string::npos);
  EXPECT_GE(s->refused(), 13u);
}

TEST(Session, AClientThatNeverReadsItsRepliesCostsABoundedQueue) {
  auto s = std::make_unique<Session>(1);
  for (int i = 0; i < 100; ++i) s->on_text(R"({"op":"nope"})");
  std::size_t replies = 0;
  while (s->has_reply()) {
    s->pop_reply();
    ++replies;
  }
  EXPECT_EQ(replies, Session::kMaxStatuses);
  EXPECT_EQ(s->replies_dropped(), 100u - Session::kMaxStatuses);
}

TEST(Session, ServerMessagesAreTheProtocolsJson) {
  const ChannelSpec specs[] = {{"/map", Schema::grid, 64}, {"/mission", Schema::mission, 64}};
  auto board = ChannelBoard::create(specs, 32, heap());
  ASSERT_TRUE(board);
  std::vector<char> buffer(64 * 1024);
  auto advertise = write_advertise(buffer, **board);
  ASSERT_TRUE(advertise);
  json::StaticDocument<4096> doc(json::Limits{32, 1 << 20});
  ASSERT_TRUE(doc.parse(*advertise));
  const auto channels = doc.root().find("channels");
  ASSERT_EQ(channels.size(), 2u);
  const auto first = *channels.items().begin();
  EXPECT_TRUE(first.find("topic").string_equals("/map"));
  EXPECT_TRUE(first.find("schemaName").string_equals("foxglove.Grid"));
  EXPECT_TRUE(first.find("encoding").string_equals("json"));
  EXPECT_TRUE(first.find("schemaEncoding").string_equals("jsonschema"));
  EXPECT_EQ(*first.find("id").uint32(), 0u);
  auto info = write_server_info(buffer, "sen3bot", "1");
  ASSERT_TRUE(info);
  ASSERT_TRUE(doc.parse(*info));
  EXPECT_EQ(doc.root().find("capabilities").size(), 0u);  // read-only: no clientPublish, no parameters
  std::array<char, kFrameHeader> header{};
  write_frame_header(header, 0x01020304u, 0x1122334455667788);
  EXPECT_EQ(header[0], 1);
  EXPECT_EQ(header[1], 4);
  EXPECT_EQ(header[4], 1);
  EXPECT_EQ(static_cast<unsigned char>(header[5]), 0x88);
  EXPECT_EQ(header[12], 0x11);
}

// --- The server over sockets -------------------------------------------------------------

struct Running {
  std::unique_ptr<Server> server;
  int port = 0;
};

Running start(ServerConfig config = {}, std::vector<ChannelSpec> specs = {}) {
  if (specs.empty()) specs = {{"/a", Schema::mission, 4096}, {"/b", Schema::task_stats, 4096}};
  config.port = 0;
  auto created = Server::create(config, specs, heap());
  EXPECT_TRUE(created) << created.error().c_str();
  if (!created) return {};
  Running r{std::move(*created), 0};
  EXPECT_TRUE(r.server->start());
  r.port = r.server->port();
  EXPECT_GT(r.port, 0);
  return r;
}

// Connects, reads serverInfo and advertise, subscribes channel i as 100 + i.
std::unique_ptr<WsClient> viewer(int port, std::size_t channels, const std::string& host = "127.0.0.1",
                                 const std::string& path = "/") {
  auto c = std::make_unique<WsClient>();
  const std::string head = c->connect(host, port, path);
  EXPECT_NE(head.find(" 101 "), std::string::npos) << head;
  EXPECT_NE(c->read().payload.find("serverInfo"), std::string_view::npos);
  EXPECT_NE(c->read().payload.find("advertise"), std::string_view::npos);
  std::string sub = R"({"op":"subscribe","subscriptions":[)";
  for (std::size_t i = 0; i < channels; ++i)
    sub += (i ? "," : "") + std::string(R"({"id":)") + std::to_string(100 + i) + R"(,"channelId":)" + std::to_string(i) + "}";
  c->send_text(sub + "]}");
  return c;
}

void publish(Server& s, std::size_t ch, std::string_view text, hal::Nanos stamp) {
  put(s.board(), ch, text, stamp);
  s.board().publish(ch);
  s.notify();
}

// The next message data frame's subscription id and payload.
std::pair<std::uint32_t, std::string> next_message(WsClient& c, int timeout_ms = 2000) {
  for (;;) {
    const WsClient::Frame f = c.read(timeout_ms);
    if (f.opcode < 0) return {0, {}};
    if (f.opcode != 2) continue;
    if (f.payload.size() < kFrameHeader || f.payload[0] != 1) return {0, "bad frame"};
    std::uint32_t id = 0;
    std::memcpy(&id, f.payload.data() + 1, 4);
    return {id, std::string(f.payload.substr(kFrameHeader))};
  }
}

TEST(Server, ServesThePageAndRefusesOtherPaths) {
  Running r = start();
  auto [status, body] = WsClient::http_get("127.0.0.1", r.port, "/");
  EXPECT_EQ(status, 200);
  EXPECT_NE(body.find("<canvas"), std::string::npos);
  EXPECT_EQ(body.find("http://"), std::string::npos) << "the page loads nothing from elsewhere";
  EXPECT_EQ(WsClient::http_get("127.0.0.1", r.port, "/etc/passwd").first, 404);
  EXPECT_EQ(WsClient::http_get("127.0.0.1", r.port, "/index.htm").first, 404);
  EXPECT_EQ(r.server->counters().pages, 1u);
}

TEST(Server, AViewerGetsTheNewestMessageOfEachSubscribedChannelAndNothingElse) {
  Running r = start();
  auto c = viewer(r.port, 1);  // only /a
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  publish(*r.server, 1, R"({"b":1})", 5);
  publish(*r.server, 0, R"({"a":1})", 7);
  auto [id, payload] = next_message(*c);
  EXPECT_EQ(id, 100u);
  EXPECT_EQ(payload, R"({"a":1})");
  // Unsubscribed: nothing more from /a.
  c->send_text(R"({"op":"unsubscribe","subscriptionIds":[100]})");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  publish(*r.server, 0, R"({"a":2})", 8);
  EXPECT_EQ(next_message(*c, 300).first, 0u);
  // Subscribed again: the newest publish comes at once.
  c->send_text(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":0}]})");
  auto [id2, payload2] = next_message(*c);
  EXPECT_EQ(id2, 5u);
  EXPECT_EQ(payload2, R"({"a":2})");
  EXPECT_EQ(r.server->counters().clients, 1u);
}

TEST(Server, RefusesAWrongSubprotocolAndMoreViewersThanConfigured) {
  ServerConfig config;
  config.max_clients = 1;
  Running r = start(config);
  WsClient wrong;
  EXPECT_EQ(wrong.connect("127.0.0.1", r.port, "/", "chat").find(" 101 "), std::string::npos);
  WsClient none;
  EXPECT_EQ(none.connect("127.0.0.1", r.port, "/", "").find(" 101 "), std::string::npos);
  auto first = viewer(r.port, 2);
  WsClient second;
  const std::string head = second.connect("127.0.0.1", r.port);
  EXPECT_NE(head.find(" 503 "), std::string::npos) << head;
  // libwebsockets turns an unknown subprotocol away before the server sees it: two are counted.
  EXPECT_GE(r.server->counters().rejected, 2u);
  publish(*r.server, 0, "{}", 1);
  EXPECT_EQ(next_message(*first).first, 100u);  // the first viewer is unaffected
}

TEST(Server, AnOversizedClientMessageClosesThatConnectionOnly) {
  Running r = start();
  auto good = viewer(r.port, 1);
  auto bad = viewer(r.port, 1);
  bad->send_text(std::string(Server::kMaxClientMessageBytes + 10, ' '));
  WsClient::Frame f;
  do f = bad->read(); while (f.opcode == 1 || f.opcode == 2);
  ASSERT_EQ(f.opcode, 8) << "expected a close frame";
  ASSERT_GE(f.payload.size(), 2u);
  EXPECT_EQ((static_cast<unsigned char>(f.payload[0]) << 8) | static_cast<unsigned char>(f.payload[1]), 1009);
  EXPECT_EQ(r.server->counters().closed_oversized, 1u);
  publish(*r.server, 0, R"({"still":"here"})", 1);
  EXPECT_EQ(next_message(*good).second, R"({"still":"here"})");
}

TEST(Server, MalformedFramesCloseThatConnectionAndTheServerCarriesOn) {
  Running r = start();
  auto good = viewer(r.port, 1);
  const std::string frames[] = {
      std::string("\xC1\x80\x00\x00\x00\x00", 6),  // a reserved bit (RSV1) without an extension
      std::string("\x83\x80\x00\x00\x00\x00", 6),  // opcode 3 is reserved
      std::string("\x09\x80\x00\x00\x00\x00", 6),  // a fragmented ping (control frames may not be)
      // A length of 2^63 - 1 (then 70 KiB of it): the message limit closes it.
      std::string("\x81\xFF\x7F\xFF\xFF\xFF\xFF\xFF\xFF\xFF\x00\x00\x00\x00", 14) + std::string(70 * 1024, 'x'),
  };
  for (const std::string& frame : frames) {
    auto bad = viewer(r.port, 1);
    bad->send_raw(frame);
    WsClient::Frame f;
    int frames_read = 0;
    do f = bad->read(2000); while ((f.opcode == 1 || f.opcode == 2) && ++frames_read < 100);
    if (f.opcode == 8) {
      ASSERT_GE(f.payload.size(), 2u);
      const int code = (static_cast<unsigned char>(f.payload[0]) << 8) | static_cast<unsigned char>(f.payload[1]);
      EXPECT_TRUE(code == 1002 || code == 1009) << code;
    } else {
      EXPECT_TRUE(bad->peer_closed()) << "the connection stays open after a malformed frame";
    }
  }
  publish(*r.server, 0, R"({"n":1})", 1);
  EXPECT_EQ(next_message(*good).second, R"({"n":1})");
  EXPECT_EQ(r.server->counters().clients, 1u);
}

TEST(Server, AStalledViewerNeverHoldsUpThePublisherNorTheOtherViewers) {
  // Large messages, so the stalled viewer's socket fills within a few publishes.
  ServerConfig config;
  Running r = start(config, {{"/big", Schema::grid, 256 * 1024}});
  auto stalled = viewer(r.port, 1);
  stalled->small_receive_buffer();
  auto reader = viewer(r.port, 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> read_count{0};
  std::thread reading([&] {
    while (!stop.load())
      if (next_message(*reader, 200).first == 100u) ++read_count;
  });
  const std::string big(200 * 1024, 'x');
  const int publishes = 200;
  std::vector<std::int64_t> publish_ns;
  publish_ns.reserve(publishes);
  for (int i = 0; i < publishes; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    publish(*r.server, 0, big, i);
    publish_ns.push_back(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::sort(publish_ns.begin(), publish_ns.end());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  stop = true;
  reading.join();
  // The reading viewer kept up; the stalled one was sent only what its socket took, then
  // nothing: it misses messages, and nothing waits for it.
  EXPECT_GT(read_count.load(), publishes / 4u);
  EXPECT_LT(r.server->counters().sent, read_count.load() + publishes / 4u);
  // Publishing is a copy and an index swap whatever the viewers do: far below a task's period.
  // A publish that waited for the server would wait on most publishes once the stalled socket is
  // full; the 95th percentile leaves out the few a busy machine preempts.
  const std::int64_t p95_ns = publish_ns[publish_ns.size() * 95 / 100];
  EXPECT_LT(p95_ns, 20'000'000) << "a publish waited for the server; slowest " << publish_ns.back() / 1'000'000 << " ms";
  EXPECT_EQ(r.server->counters().clients, 2u);
}

TEST(Server, CreateRefusesANonLoopbackAddressWithoutATokenAndBadSettings) {
  const ChannelSpec specs[] = {{"/a", Schema::mission, 64}};
  ServerConfig open;
  open.address = "0.0.0.0";
  auto refused = Server::create(open, specs, heap());
  ASSERT_FALSE(refused);
  EXPECT_NE(std::string(refused.error().c_str()).find("token"), std::string::npos);
  ServerConfig name;
  name.address = "localhost";  // not an address
  EXPECT_FALSE(Server::create(name, specs, heap()));
  ServerConfig spaces;
  spaces.address = "0.0.0.0";
  spaces.token = "a b";
  EXPECT_FALSE(Server::create(spaces, specs, heap()));
  ServerConfig clients;
  clients.max_clients = 0;
  EXPECT_FALSE(Server::create(clients, specs, heap()));
}

TEST(Server, LoopbackAndTokenRules) {
  EXPECT_TRUE(is_loopback_address("127.0.0.1"));
  EXPECT_TRUE(is_loopback_address("127.1.2.3"));
  EXPECT_TRUE(is_loopback_address("::1"));
  EXPECT_TRUE(is_loopback_address("::ffff:127.0.0.1"));
  EXPECT_FALSE(is_loopback_address("0.0.0.0"));
  EXPECT_FALSE(is_loopback_address("10.0.0.1"));
  EXPECT_FALSE(is_loopback_address("::"));
  EXPECT_FALSE(is_loopback_address("128.0.0.1"));
  EXPECT_TRUE(token_matches("s3cret", "s3cret"));
  EXPECT_FALSE(token_matches("s3cre", "s3cret"));
  EXPECT_FALSE(token_matches("s3cretX", "s3cret"));
  EXPECT_FALSE(token_matches("", ""));  // no token configured: nothing matches
}

// This machine's first non-loopback IPv4 address, or "".
std::string own_address() {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return {};
  std::string found;
  for (ifaddrs* a = list; a != nullptr && found.empty(); a = a->ifa_next) {
    if (a->ifa_addr == nullptr || a->ifa_addr->sa_family != AF_INET || (a->ifa_flags & IFF_LOOPBACK)) continue;
    char text[INET_ADDRSTRLEN];
    inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ifa_addr)->sin_addr, text, sizeof text);
    found = text;
  }
  freeifaddrs(list);
  return found;
}

TEST(Server, AViewerFromAnotherMachineNeedsTheToken) {
  const std::string address = own_address();
  if (address.empty()) GTEST_SKIP() << "no non-loopback IPv4 address on this machine";
  ServerConfig config;
  config.address = "0.0.0.0";
  config.token = "Xy9-tok_en";
  Running r = start(config);
  // The page and the WebSocket alike.
  EXPECT_EQ(WsClient::http_get(address, r.port, "/").first, 401);
  EXPECT_EQ(WsClient::http_get(address, r.port, "/?token=wrong").first, 401);
  EXPECT_EQ(WsClient::http_get(address, r.port, "/?token=Xy9-tok_en").first, 200);
  EXPECT_EQ(WsClient::http_get(address, r.port, "/", "Authorization: Bearer Xy9-tok_en\r\n").first, 200);
  WsClient anonymous;
  EXPECT_NE(anonymous.connect(address, r.port).find(" 401 "), std::string::npos);
  WsClient wrong;
  EXPECT_NE(wrong.connect(address, r.port, "/?token=Xy9-tok_eN").find(" 401 "), std::string::npos);
  auto c = viewer(r.port, 1, address, "/?token=Xy9-tok_en");
  publish(*r.server, 0, "{}", 1);
  EXPECT_EQ(next_message(*c).first, 100u);
  // Loopback needs none.
  EXPECT_EQ(WsClient::http_get("127.0.0.1", r.port, "/").first, 200);
  EXPECT_GE(r.server->counters().rejected, 4u);
}

}  // namespace
}  // namespace sen3bot::view
