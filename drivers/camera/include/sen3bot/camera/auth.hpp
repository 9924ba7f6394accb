#pragma once
// RTSP authentication: Basic (RFC 2617 §2) and Digest MD5 (RFC 2617 §3, including the
// RFC 2069 form without qop that GStreamer and many cameras use). Pure except for the
// cnonce, which comes from the caller.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera {

struct Credentials {
  std::string user;
  std::string password;
  [[nodiscard]] bool empty() const { return user.empty(); }
};

enum class AuthScheme : std::uint8_t { none, basic, digest };

struct AuthChallenge {
  AuthScheme scheme = AuthScheme::none;
  std::string realm;
  std::string nonce;
  std::string opaque;
  std::string algorithm;  // as sent; empty means MD5
  bool qop_auth = false;  // the challenge offered qop=auth
  bool stale = false;
};

// One WWW-Authenticate value. Errc::protocol when it is neither Basic nor Digest.
Result<AuthChallenge> parse_challenge(std::string_view value);

// Picks from every WWW-Authenticate header of a 401: Digest with MD5 first, then Basic.
// Errc::not_supported when nothing usable was offered (e.g. only SHA-256 Digest).
Result<AuthChallenge> choose_challenge(std::span<const std::string_view> values);

std::string md5_hex(std::string_view data);
std::string base64_encode(std::span<const std::uint8_t> data);
// Standard alphabet; whitespace is skipped; Errc::invalid_argument on anything else.
Result<std::vector<std::uint8_t>> base64_decode(std::string_view text);

// The digest "response" value (RFC 2617 §3.2.2.1). qop empty = RFC 2069 form.
std::string digest_response(std::string_view user, std::string_view realm, std::string_view password,
                            std::string_view method, std::string_view uri, std::string_view nonce,
                            std::string_view qop, std::string_view nc, std::string_view cnonce);

// Holds the last challenge and builds an Authorization value for each request. uri must be
// the exact Request-URI of that request, without userinfo.
class Authenticator {
 public:
  void set_credentials(Credentials credentials) { credentials_ = std::move(credentials); }
  void set_challenge(AuthChallenge challenge);
  void reset() { challenge_ = {}; nonce_count_ = 0; }
  [[nodiscard]] bool active() const { return challenge_.scheme != AuthScheme::none && !credentials_.empty(); }
  [[nodiscard]] bool has_credentials() const { return !credentials_.empty(); }
  [[nodiscard]] const std::string& user() const { return credentials_.user; }

  // Empty when no challenge has been seen. cnonce is used only with qop=auth.
  std::string authorization(std::string_view method, std::string_view uri, std::string_view cnonce);

 private:
  Credentials credentials_;
  AuthChallenge challenge_;
  std::uint32_t nonce_count_ = 0;
};

}  // namespace sen3bot::camera
