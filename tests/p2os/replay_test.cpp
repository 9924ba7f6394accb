// The checked-in session capture: decoding it gives exactly the checked-in JSON lines, and a
// driver replayed against it on the same time line sends exactly the recorded bytes.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/p2os/describe.hpp"
#include "session.hpp"

namespace sen3bot::p2os {
namespace {

const std::string kCapture = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/p2os_session.s3bcap";
const std::string kDecoded = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/p2os_session.jsonl";

TEST(P2osReplay, DecodesToTheCheckedInLines) {
  auto capture = capture::CaptureFile::load(kCapture);
  ASSERT_TRUE(capture) << capture.error().c_str();
  std::ostringstream decoded;
  ASSERT_TRUE(decode_capture(*capture, "", [&](const std::string& line) { decoded << line << '\n'; }));
  std::ifstream in(kDecoded);
  std::stringstream expected;
  expected << in.rdbuf();
  ASSERT_FALSE(expected.str().empty());
  EXPECT_EQ(decoded.str(), expected.str());
  // The session has what it should: handshake, config, SIPs, encoders, a clean close.
  const std::string text = decoded.str();
  EXPECT_NE(text.find("\"subclass\":\"p3dx-sh\""), std::string::npos);
  EXPECT_NE(text.find("\"type\":\"CONFIGpac\""), std::string::npos);
  EXPECT_NE(text.find("\"type\":\"ENCODERpac\""), std::string::npos);
  EXPECT_NE(text.find("\"type\":\"SYNC2/CLOSE\""), std::string::npos);
  EXPECT_NE(text.find("\"rx_bad_checksums\":0,\"tx_bad_checksums\":0"), std::string::npos);
}

// The recording ends with the robot's last packet while the driver is still closing: past
// that point the replay reads as a quiet line, not as a vanished device.
class QuietAfterEnd final : public hal::ByteStream {
 public:
  explicit QuietAfterEnd(capture::ReplayStream& replay) : replay_(replay) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override {
    if (replay_.finished()) return std::size_t{0};
    return replay_.read(out);
  }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override { return replay_.write(data); }
  [[nodiscard]] std::string_view name() const override { return replay_.name(); }

 private:
  capture::ReplayStream& replay_;
};

TEST(P2osReplay, DriverReplaysByteIdentically) {
  auto capture = capture::CaptureFile::load(kCapture);
  ASSERT_TRUE(capture) << capture.error().c_str();
  hal::SimClock clock(hal::seconds(100));
  capture::ReplayStream replay(*capture, 0, clock, capture::ReplayTiming::original);
  QuietAfterEnd link(replay);
  const BaseState final_state = test::run_session(link, clock, {});
  const capture::TxComparison& tx = replay.tx_comparison();
  EXPECT_TRUE(tx.identical()) << "first mismatch at tx offset " << tx.first_mismatch_offset << ": expected "
                              << tx.first_mismatch_expected << ", got " << tx.first_mismatch_actual;
  EXPECT_EQ(final_state.link, LinkState::closed);
  EXPECT_GT(final_state.sip_count, 20u);
  EXPECT_TRUE(final_state.encoders_valid);
  EXPECT_GT(final_state.distance_m, 0.3);
}

}  // namespace
}  // namespace sen3bot::p2os
