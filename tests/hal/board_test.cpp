// The robot computer's board: links through open_byte_stream with the serial line's rate
// control, clear errors naming the link or the GPIO line, and a listener on the lockstep clock.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sen3bot/hal/board.hpp"
#include "sen3bot/hal/pty.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::hal {
namespace {

TEST(PosixBoard, ASerialLinkComesWithItsRateControl) {
  Result<std::unique_ptr<PtyPair>> pty = PtyPair::open();
  ASSERT_TRUE(pty) << pty.error().c_str();
  PosixBoard board;
  Result<Link> link = board.open_link("laser", LinkRequest{(*pty)->slave_path(), 9600});
  ASSERT_TRUE(link) << link.error().c_str();
  ASSERT_NE(link->baud_control, nullptr);
  EXPECT_EQ(link->baud, 9600u);
  ASSERT_TRUE(link->baud_control->set_baud(38400));
  Result<std::uint32_t> seen = (*pty)->slave_baud();
  ASSERT_TRUE(seen);
  EXPECT_EQ(*seen, 38400u);
  const std::uint8_t byte[] = {0x02};
  ASSERT_TRUE(link->stream->write(byte));
}

TEST(PosixBoard, ATcpLinkHasNoRateAndAFailedOpenNamesTheLink) {
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("127.0.0.1", 0);
  ASSERT_TRUE(listener) << listener.error().c_str();
  PosixBoard board;
  Result<Link> link =
      board.open_link("base", LinkRequest{"tcp://127.0.0.1:" + std::to_string((*listener)->port()), 9600, 1000});
  ASSERT_TRUE(link) << link.error().c_str();
  EXPECT_EQ(link->baud_control, nullptr);
  EXPECT_EQ(link->baud, 0u);

  Result<Link> missing = board.open_link("base", LinkRequest{"/dev/no-such-tty", 9600});
  ASSERT_FALSE(missing);
  const std::string m(missing.error().message());
  EXPECT_NE(m.find("base link: "), std::string::npos) << m;
  EXPECT_NE(m.find("/dev/no-such-tty"), std::string::npos) << m;
}

TEST(PosixBoard, GpioLinesAreCheckedAtOpen) {
  PosixBoard none;
  EXPECT_TRUE(none.open_lines());
  EXPECT_EQ(none.input("estop"), nullptr);
  EXPECT_EQ(none.output("light"), nullptr);

  PosixBoard bad_spec(PosixBoard::Lines{"/dev/gpiochip0", ""});
  Status s = bad_spec.open_lines();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::config);
  EXPECT_NE(std::string(s.error().message()).find("estop input: gpio: '/dev/gpiochip0': expected /dev/gpiochipN:LINE"),
            std::string::npos)
      << s.error().c_str();

  PosixBoard missing(PosixBoard::Lines{"", "/dev/gpiochip-none:27"});
  s = missing.open_lines();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::not_found);
  EXPECT_NE(std::string(s.error().message()).find("light output: gpio: open /dev/gpiochip-none"), std::string::npos)
      << s.error().c_str();
}

class Recorder final : public SimClock::Listener {
 public:
  void before_advance(Nanos now_ns, Nanos to_ns) override { calls.push_back({now_ns, to_ns}); }
  std::vector<std::pair<Nanos, Nanos>> calls;
};

TEST(SimClockListener, IsToldBeforeTimeMovesAndNeverForThePast) {
  SimClock clock(100);
  Recorder recorder;
  clock.set_listener(&recorder);
  clock.advance_to(150);
  clock.advance_to(120);  // the past: not told, time stays
  clock.advance_by(10);
  clock.sleep_until(160);
  ASSERT_EQ(recorder.calls.size(), 3u);
  EXPECT_EQ(recorder.calls[0], (std::pair<Nanos, Nanos>{100, 150}));
  EXPECT_EQ(recorder.calls[1], (std::pair<Nanos, Nanos>{150, 160}));
  EXPECT_EQ(recorder.calls[2], (std::pair<Nanos, Nanos>{160, 160}));
  EXPECT_EQ(clock.now(), 160);
}

}  // namespace
}  // namespace sen3bot::hal
