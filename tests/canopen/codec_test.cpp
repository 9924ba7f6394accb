#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string_view>

#include "sen3bot/canopen/codec.hpp"

namespace sen3bot::canopen {
namespace {


CanFrame frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.dlc = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (const std::uint8_t b : bytes) f.data[i++] = b;
  return f;
}

TEST(CanopenCodec, EveryCobIdOfTheConnectionSetIsClassified) {
  EXPECT_EQ(classify(frame(0x000, {1, 0})).kind, Kind::nmt);
  EXPECT_EQ(classify(frame(0x080, {})).kind, Kind::sync);
  const struct {
    std::uint32_t base;
    Kind kind;
    std::uint8_t pdo;
  } cases[] = {{0x080, Kind::emcy, 0},         {0x180, Kind::tpdo, 1}, {0x200, Kind::rpdo, 1},
               {0x280, Kind::tpdo, 2},         {0x300, Kind::rpdo, 2}, {0x380, Kind::tpdo, 3},
               {0x400, Kind::rpdo, 3},         {0x480, Kind::tpdo, 4}, {0x500, Kind::rpdo, 4},
               {0x580, Kind::sdo_response, 0}, {0x600, Kind::sdo_request, 0}, {0x700, Kind::heartbeat, 0}};
  for (const auto& c : cases) {
    for (const std::uint8_t node : {std::uint8_t{1}, std::uint8_t{5}, std::uint8_t{127}}) {
      const Classified k = classify(frame(c.base + node, {0}));
      EXPECT_EQ(k.kind, c.kind) << std::hex << c.base + node;
      EXPECT_EQ(k.node, node);
      EXPECT_EQ(k.pdo, c.pdo);
    }
  }
  // Node 0 of a node's function, extended ids and remote frames are not CANopen objects.
  EXPECT_EQ(classify(frame(0x700, {0})).kind, Kind::other);
  CanFrame ext = frame(0x185, {1});
  ext.extended = true;
  EXPECT_EQ(classify(ext).kind, Kind::other);
  CanFrame rtr = frame(0x705, {});
  rtr.rtr = true;
  EXPECT_EQ(classify(rtr).kind, Kind::other);
  EXPECT_EQ(classify(frame(0x7E5, {0})).kind, Kind::other);  // LSS, not spoken
}

TEST(CanopenCodec, NmtAndHeartbeatRoundTrip) {
  Result<CanFrame> start = nmt(NmtCommand::start, 5);
  ASSERT_TRUE(start);
  EXPECT_EQ(*start, frame(0x000, {0x01, 0x05}));
  Result<Nmt> back = decode_nmt(*start);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->command, NmtCommand::start);
  EXPECT_EQ(back->node, 5);
  EXPECT_EQ(*nmt(NmtCommand::reset_node, 0), frame(0x000, {0x81, 0x00}));  // every node
  EXPECT_FALSE(nmt(NmtCommand::stop, 128));
  EXPECT_FALSE(decode_nmt(frame(0x000, {0x03, 0x05})));  // no such command
  EXPECT_FALSE(decode_nmt(frame(0x000, {0x01})));        // short

  EXPECT_EQ(*heartbeat(5, NmtState::operational), frame(0x705, {0x05}));
  Result<Heartbeat> hb = decode_heartbeat(frame(0x705, {0x7F}));
  ASSERT_TRUE(hb);
  EXPECT_EQ(hb->node, 5);
  EXPECT_EQ(hb->state, NmtState::pre_operational);
  Result<Heartbeat> boot = decode_heartbeat(frame(0x70A, {0x00}));
  ASSERT_TRUE(boot);
  EXPECT_EQ(boot->state, NmtState::boot_up);
  Result<Heartbeat> toggled = decode_heartbeat(frame(0x705, {0x85}));  // node guarding's toggle bit
  ASSERT_TRUE(toggled);
  EXPECT_TRUE(toggled->toggle);
  EXPECT_EQ(toggled->state, NmtState::operational);
  Result<Heartbeat> bad = decode_heartbeat(frame(0x705, {0x06}));
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message().find("state 0x06"), std::string_view::npos) << bad.error().message();
  EXPECT_FALSE(decode_heartbeat(frame(0x705, {})));
  EXPECT_FALSE(decode_heartbeat(frame(0x185, {0x05})));
  EXPECT_FALSE(heartbeat(0, NmtState::operational));
}

// The bytes of CiA 301's expedited transfers, written out by hand.
TEST(CanopenCodec, SdoExpeditedTransfersHaveTheStandardsBytes) {
  // Read 0x1017:00 (producer heartbeat time) from node 5.
  EXPECT_EQ(*sdo_upload_request(5, {0x1017, 0}), frame(0x605, {0x40, 0x17, 0x10, 0x00, 0, 0, 0, 0}));
  // Its answer: 500 ms, two bytes.
  const CanFrame answer = frame(0x585, {0x4B, 0x17, 0x10, 0x00, 0xF4, 0x01, 0, 0});
  EXPECT_EQ(*sdo_upload_response(5, {0x1017, 0}, 500, 2), answer);
  Result<Sdo> read = decode_sdo(answer);
  ASSERT_TRUE(read) << read.error().message();
  EXPECT_EQ(read->type, SdoType::upload_response);
  EXPECT_EQ(read->node, 5);
  EXPECT_EQ(read->at, (SdoAddress{0x1017, 0}));
  EXPECT_EQ(read->value, 500u);
  EXPECT_EQ(read->size, 2);
  // Write 0x6200:01 = 0x0F (the outputs), one byte; and a four-byte write.
  EXPECT_EQ(*sdo_download_request(5, {0x6200, 1}, 0x0F, 1), frame(0x605, {0x2F, 0x00, 0x62, 0x01, 0x0F, 0, 0, 0}));
  EXPECT_EQ(*sdo_download_request(5, {0x1017, 0}, 0x12345678, 4),
            frame(0x605, {0x23, 0x17, 0x10, 0x00, 0x78, 0x56, 0x34, 0x12}));
  EXPECT_EQ(sdo_download_request(5, {0x1017, 0}, 0xABCDEF, 3)->data[0], 0x27);
  // Only the size's bytes are sent.
  EXPECT_EQ(*sdo_download_request(5, {0x6200, 1}, 0x1FF, 1), frame(0x605, {0x2F, 0x00, 0x62, 0x01, 0xFF, 0, 0, 0}));
  EXPECT_EQ(*sdo_download_response(5, {0x6200, 1}), frame(0x585, {0x60, 0x00, 0x62, 0x01, 0, 0, 0, 0}));
  // An abort: object does not exist.
  const CanFrame abort = frame(0x585, {0x80, 0x00, 0x70, 0x00, 0x00, 0x00, 0x02, 0x06});
  EXPECT_EQ(*sdo_abort(5, {0x7000, 0}, abort_code::kNoObject, true), abort);
  Result<Sdo> aborted = decode_sdo(abort);
  ASSERT_TRUE(aborted);
  EXPECT_EQ(aborted->type, SdoType::abort);
  EXPECT_EQ(aborted->value, abort_code::kNoObject);
  EXPECT_STREQ(describe_abort(aborted->value), "object does not exist in the object dictionary");
  EXPECT_STREQ(describe_abort(0x12345678), "unknown abort code");
  // Bad arguments.
  EXPECT_FALSE(sdo_download_request(5, {0x6200, 1}, 1, 0));
  EXPECT_FALSE(sdo_download_request(5, {0x6200, 1}, 1, 5));
  EXPECT_FALSE(sdo_upload_request(0, {0x1000, 0}));
}

TEST(CanopenCodec, EveryDecodedSdoEncodesToTheSameFrame) {
  for (const std::uint8_t size : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{3}, std::uint8_t{4}}) {
    const CanFrame request = *sdo_download_request(9, {0x2000, 3}, 0xA1B2C3D4, size);
    Result<Sdo> r = decode_sdo(request);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->type, SdoType::download_request);
    EXPECT_EQ(r->size, size);
    EXPECT_EQ(*sdo_download_request(r->node, r->at, r->value, r->size), request);
    const CanFrame response = *sdo_upload_response(9, {0x2000, 3}, 0xA1B2C3D4, size);
    Result<Sdo> u = decode_sdo(response);
    ASSERT_TRUE(u);
    EXPECT_EQ(*sdo_upload_response(u->node, u->at, u->value, u->size), response);
  }
}

TEST(CanopenCodec, SdoTransfersItDoesNotSpeakAreRefusedWithTheReason) {
  // A segmented upload response (e = 0): the object is longer than 4 bytes.
  Result<Sdo> segmented = decode_sdo(frame(0x585, {0x41, 0x08, 0x10, 0x00, 0x10, 0, 0, 0}));
  ASSERT_FALSE(segmented);
  EXPECT_EQ(segmented.error().code(), Errc::protocol);
  EXPECT_NE(segmented.error().message().find("segmented"), std::string_view::npos) << segmented.error().message();
  // A block transfer command (client 6), a short frame, and a frame that is no SDO.
  EXPECT_FALSE(decode_sdo(frame(0x605, {0xC0, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_FALSE(decode_sdo(frame(0x585, {0x4B, 0x17, 0x10})));
  EXPECT_FALSE(decode_sdo(frame(0x185, {0x4B, 0x17, 0x10, 0, 0, 0, 0, 0})));
  // A download request from the server's side is not an answer.
  EXPECT_FALSE(decode_sdo(frame(0x585, {0x2F, 0x00, 0x62, 0x01, 0x0F, 0, 0, 0})));
}

TEST(CanopenCodec, EmergenciesAndPdos) {
  Emergency e;
  e.code = 0x8130;
  e.error_register = 0x11;
  e.vendor = {1, 2, 3, 4, 5};
  const CanFrame f = *emergency(5, e);
  EXPECT_EQ(f, frame(0x085, {0x30, 0x81, 0x11, 1, 2, 3, 4, 5}));
  Result<Emergency> back = decode_emergency(f);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->code, 0x8130);
  EXPECT_EQ(back->error_register, 0x11);
  EXPECT_EQ(back->vendor, e.vendor);
  EXPECT_STREQ(describe_emergency(0x8130), "heartbeat or life guard error");
  EXPECT_STREQ(describe_emergency(0x0000), "error reset or no error");
  EXPECT_STREQ(describe_emergency(0x3210), "voltage");
  EXPECT_STREQ(describe_emergency(0xFF01), "device specific");
  EXPECT_FALSE(decode_emergency(frame(0x085, {0x30, 0x81})));

  const std::array<std::uint8_t, 1> inputs = {0x81};
  EXPECT_EQ(*pdo(5, 1, true, inputs), frame(0x185, {0x81}));
  EXPECT_EQ(*pdo(5, 1, false, inputs), frame(0x205, {0x81}));
  EXPECT_EQ(pdo(5, 4, true, inputs)->id, 0x485u);
  EXPECT_FALSE(pdo(5, 5, true, inputs));
  const std::array<std::uint8_t, 9> too_long{};
  EXPECT_FALSE(pdo(5, 1, true, too_long));
}

}  // namespace
}  // namespace sen3bot::canopen
