#include <gtest/gtest.h>

#include <string_view>

#include "sen3bot/camera/auth.hpp"

namespace sen3bot::camera {
namespace {

// RFC 2617 §3.5 and the vectors computed in the brief (§1.6).
TEST(Auth, DigestVectors) {
  EXPECT_EQ(digest_response("Mufasa", "testrealm@host.com", "Circle Of Life", "GET", "/dir/index.html",
                            "dcd98b7102dd2f0e8b11d0f600bfb0c093", "auth", "00000001", "0a4f113b"),
            "6629fae49393a05397450978507c4ef1");
  EXPECT_EQ(digest_response("Mufasa", "testrealm@host.com", "Circle Of Life", "GET", "/dir/index.html",
                            "dcd98b7102dd2f0e8b11d0f600bfb0c093", "", "", ""),
            "670fd8c2df070c60b045671b8b24ff02");
  EXPECT_EQ(digest_response("admin", "GStreamer RTSP Server", "secret", "DESCRIBE", "rtsp://127.0.0.1:8555/mjpeg",
                            "66641f03e29ce50b", "", "", ""),
            "121267589963d36438491983ee203519");
}

TEST(Auth, BasicHeader) {
  Authenticator a;
  a.set_credentials({"admin", "secret"});
  const std::string_view challenges[] = {"Basic realm=\"cam\""};
  a.set_challenge(*choose_challenge(challenges));
  EXPECT_EQ(a.authorization("DESCRIBE", "rtsp://h/", ""), "Basic YWRtaW46c2VjcmV0");
}

TEST(Auth, PrefersDigestMd5OverBasicAndSha256) {
  const std::string_view challenges[] = {"Basic realm=\"x\"", "Digest realm=\"x\", nonce=\"1\", algorithm=SHA-256",
                                         "Digest realm=\"Surveillance Server\", nonce=\"98481030\", algorithm=MD5"};
  auto c = choose_challenge(challenges);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->scheme, AuthScheme::digest);
  EXPECT_EQ(c->nonce, "98481030");
  const std::string_view only_sha[] = {"Digest realm=\"x\", nonce=\"1\", algorithm=SHA-256"};
  EXPECT_EQ(choose_challenge(only_sha).error().code(), Errc::not_supported);
  const std::string_view junk[] = {"Bearer x", "Digest realm=\"x\""};
  EXPECT_FALSE(choose_challenge(junk).ok());
}

TEST(Auth, DigestHeaderWithoutAndWithQop) {
  Authenticator a;
  a.set_credentials({"admin", "secret"});
  a.set_challenge(*parse_challenge("Digest realm=\"GStreamer RTSP Server\", nonce=\"66641f03e29ce50b\""));
  EXPECT_EQ(a.authorization("DESCRIBE", "rtsp://127.0.0.1:8555/mjpeg", "c"),
            "Digest username=\"admin\", realm=\"GStreamer RTSP Server\", nonce=\"66641f03e29ce50b\", "
            "uri=\"rtsp://127.0.0.1:8555/mjpeg\", response=\"121267589963d36438491983ee203519\"");
  a.set_credentials({"Mufasa", "Circle Of Life"});
  a.set_challenge(*parse_challenge(
      "Digest realm=\"testrealm@host.com\", qop=\"auth,auth-int\", nonce=\"dcd98b7102dd2f0e8b11d0f600bfb0c093\", "
      "opaque=\"5ccc069c403ebaf9f0171e9517f40e41\""));
  const std::string h = a.authorization("GET", "/dir/index.html", "0a4f113b");
  EXPECT_NE(h.find("response=\"6629fae49393a05397450978507c4ef1\""), std::string::npos) << h;
  EXPECT_NE(h.find("nc=00000001"), std::string::npos);
  EXPECT_NE(h.find("opaque=\"5ccc069c403ebaf9f0171e9517f40e41\""), std::string::npos);
  EXPECT_NE(a.authorization("GET", "/dir/index.html", "0a4f113b").find("nc=00000002"), std::string::npos);
}

TEST(Auth, Base64RoundTrip) {
  for (std::string s : {"", "a", "ab", "abc", "abcd", "admin:secret"}) {
    const auto enc = base64_encode(std::span(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
    auto dec = base64_decode(enc);
    ASSERT_TRUE(dec.ok());
    EXPECT_EQ(std::string(dec->begin(), dec->end()), s);
  }
  EXPECT_FALSE(base64_decode("ab$c").ok());
  EXPECT_FALSE(base64_decode("ab=c").ok());
}

}  // namespace
}  // namespace sen3bot::camera
