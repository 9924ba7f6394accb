#include <gtest/gtest.h>

#include "camera_test_util.hpp"
#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/onvif.hpp"

namespace sen3bot::camera::onvif {
namespace {

using camera::testing::read_fixture;

// ONVIF Application Programmer's Guide vector (brief §5.3).
TEST(Onvif, PasswordDigestVectorHashesNonceBytes) {
  auto nonce = base64_decode("LKqI6G/AikKCQrN0zqZFlg==");
  ASSERT_TRUE(nonce.ok());
  EXPECT_EQ(password_digest(*nonce, "2010-09-16T07:50:45Z", "userpassword"), "tuOSpGlFlIXsozq4HFNeeGeFLEI=");
  // The classic bug, hashing the base64 text, gives another value.
  const std::string text = "LKqI6G/AikKCQrN0zqZFlg==";
  EXPECT_EQ(password_digest(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()),
                            "2010-09-16T07:50:45Z", "userpassword"),
            "YBCPSgpGYaaItaZAa5HaytT3CRM=");
}

TEST(Onvif, TokenUsesTheSameCreatedStringItHashed) {
  const std::uint8_t nonce[16] = {1, 2, 3};
  const UsernameToken t = make_username_token("admin", "pw", nonce, 1'290'000'000'123);
  EXPECT_EQ(t.created, "2010-11-17T13:20:00.123Z");
  EXPECT_EQ(t.password_digest, password_digest(nonce, t.created, "pw"));
  const std::string env = envelope(get_profiles_body(), &t);
  EXPECT_NE(env.find("<wsu:Created>" + t.created + "</wsu:Created>"), std::string::npos);
  EXPECT_NE(env.find("#PasswordDigest\">" + t.password_digest), std::string::npos);
  EXPECT_EQ(envelope(get_system_date_and_time_body(), nullptr).find("Security"), std::string::npos);
}

TEST(Onvif, RealCameraFixtures) {
  auto utc = parse_system_date_and_time(read_fixture("onvif/GetSystemDateAndTime.xml"));
  ASSERT_TRUE(utc.ok()) << utc.error().message();
  EXPECT_EQ(*utc, 1419448477000);  // 2014-12-24T19:14:37Z
  auto services = parse_services(read_fixture("onvif/GetServices.xml"));
  ASSERT_TRUE(services.ok()) << services.error().message();
  EXPECT_EQ(services->media, "http://192.168.68.111/onvif/services");
  EXPECT_EQ(services->ptz, "http://192.168.68.111/onvif/services");
  auto caps = parse_capabilities(read_fixture("onvif/GetCapabilities.xml"));
  ASSERT_TRUE(caps.ok()) << caps.error().message();
  EXPECT_EQ(caps->ptz, "http://192.168.68.111/onvif/services");
  auto profiles = parse_profiles(read_fixture("onvif/GetProfiles.xml"));
  ASSERT_TRUE(profiles.ok()) << profiles.error().message();
  ASSERT_FALSE(profiles->empty());
  EXPECT_EQ((*profiles)[0].token, "main");
  EXPECT_EQ((*profiles)[0].encoding, "H264");
  EXPECT_EQ((*profiles)[0].width_px, 1920);
  EXPECT_TRUE((*profiles)[0].has_ptz);
  auto uri = parse_media_uri(read_fixture("onvif/GetStreamUri.xml"));
  ASSERT_TRUE(uri.ok());
  EXPECT_EQ(*uri, "rtsp://192.168.68.111/h264main");
  auto snap = parse_media_uri(read_fixture("onvif/GetSnapshotUri.xml"));
  ASSERT_TRUE(snap.ok());
  EXPECT_EQ(*snap, "http://192.168.68.111/onvif-cgi/jpg/image.cgi?resolution=800x600&compression=20&camera=1");
  auto matches = parse_probe_matches(read_fixture("onvif/Probe.xml"));
  ASSERT_TRUE(matches.ok());
  ASSERT_EQ(matches->size(), 1u);
  EXPECT_EQ((*matches)[0].endpoint, "uuid:c9790c3a-701b-464d-a189-0060351c8ada");
  EXPECT_NE((*matches)[0].types.find("NetworkVideoTransmitter"), std::string::npos);
  auto no_fault = parse_fault(read_fixture("onvif/GetProfiles.xml"));
  ASSERT_TRUE(no_fault.ok());
  EXPECT_FALSE(no_fault->has_value());
  auto fault = parse_fault(read_fixture("onvif/Error.xml"));
  ASSERT_TRUE(fault.ok()) << fault.error().message();
  ASSERT_TRUE(fault->has_value());
  EXPECT_EQ((*fault)->code, "fault code");
  EXPECT_EQ((*fault)->reason, "fault reason");
}

TEST(Onvif, OtherPrefixesParseTheSame) {
  const char* node_soap =
      "<env:Envelope xmlns:env=\"http://www.w3.org/2003/05/soap-envelope\"><env:Body>"
      "<trt:GetStreamUriResponse xmlns:trt=\"http://www.onvif.org/ver10/media/wsdl\"><trt:MediaUri>"
      "<trt:Uri>rtsp://10.0.0.5:554/live?ch=1&amp;sub=0</trt:Uri><trt:Timeout>PT30S</trt:Timeout>"
      "</trt:MediaUri></trt:GetStreamUriResponse></env:Body></env:Envelope>";
  auto uri = parse_media_uri(node_soap);
  ASSERT_TRUE(uri.ok());
  EXPECT_EQ(*uri, "rtsp://10.0.0.5:554/live?ch=1&sub=0");
  const char* not_authorized =
      "<soap:Envelope xmlns:soap=\"http://www.w3.org/2003/05/soap-envelope\"><soap:Body><soap:Fault><soap:Code>"
      "<soap:Value>soap:Sender</soap:Value><soap:Subcode><soap:Value>ter:NotAuthorized</soap:Value></soap:Subcode>"
      "</soap:Code><soap:Reason><soap:Text xml:lang=\"en\">Sender not Authorized</soap:Text></soap:Reason>"
      "</soap:Fault></soap:Body></soap:Envelope>";
  auto f = parse_fault(not_authorized);
  ASSERT_TRUE(f.ok() && f->has_value());
  EXPECT_EQ((*f)->code, "soap:Sender");
  EXPECT_EQ((*f)->subcode, "ter:NotAuthorized");
}

TEST(Onvif, HostileXmlIsAClearError) {
  EXPECT_FALSE(parse_profiles("<a><b>").ok());
  EXPECT_FALSE(parse_profiles("").ok());
  EXPECT_FALSE(parse_media_uri("<x/>").ok());
  EXPECT_FALSE(parse_system_date_and_time("<UTCDateTime><Date><Year>1</Year></Date><Time/></UTCDateTime>").ok());
  EXPECT_FALSE(parse_profiles(std::string(kMaxSoapBytes + 1, ' ')).ok());
  // An external entity is not fetched nor expanded.
  const char* xxe =
      "<?xml version=\"1.0\"?><!DOCTYPE r [<!ENTITY x SYSTEM \"file:///etc/passwd\">]>"
      "<MediaUri><Uri>&x;</Uri></MediaUri>";
  auto uri = parse_media_uri(xxe);
  if (uri.ok()) {
    EXPECT_EQ(uri->find("root"), std::string::npos);
  }
}

TEST(Onvif, ProfileChoicePrefersEncodingSizeAndPtz) {
  std::vector<Profile> profiles = {{"sub", "", "H264", 640, 360, false},
                                   {"main", "", "H264", 1280, 720, true},
                                   {"mj", "", "JPEG", 1280, 720, false}};
  EXPECT_EQ(choose_profile(profiles, "H264", 1280, 720)->token, "main");
  EXPECT_EQ(choose_profile(profiles, "JPEG", 1280, 720)->token, "mj");
  EXPECT_EQ(choose_profile({}, "H264", 1, 1), nullptr);
}

TEST(Onvif, BodiesAndHelpers) {
  const std::string move = continuous_move_body("main", 2.0, -0.25, 0, 1.5);
  EXPECT_NE(move.find("x=\"1.000\" y=\"-0.250\""), std::string::npos);
  EXPECT_NE(move.find("<Timeout>PT1.500S</Timeout>"), std::string::npos);
  EXPECT_NE(stop_body("a&b").find("a&amp;b"), std::string::npos);
  EXPECT_NE(probe_message("urn:uuid:1").find("<a:MessageID>urn:uuid:1</a:MessageID>"), std::string::npos);
  EXPECT_EQ(rewrite_http_host("http://192.168.68.111/onvif/services", "127.0.0.1", 8080), "http://127.0.0.1:8080/onvif/services");
  EXPECT_EQ(rewrite_http_host("http://127.0.0.1:1000", "cam", 80), "http://cam:80");
  EXPECT_DOUBLE_EQ(*parse_duration_s("PT1093754.348S"), 1093754.348);
  EXPECT_DOUBLE_EQ(*parse_duration_s("PT1M30S"), 90.0);
  EXPECT_FALSE(parse_duration_s("P1D").has_value());
  EXPECT_FALSE(parse_duration_s("PTxS").has_value());
}

}  // namespace
}  // namespace sen3bot::camera::onvif
