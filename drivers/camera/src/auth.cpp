#include "sen3bot/camera/auth.hpp"

#include <openssl/evp.h>

#include <cstdio>

#include "sen3bot/camera/rtsp_message.hpp"

namespace sen3bot::camera {
namespace {

// key=value or key="value" pairs separated by commas (RFC 2617 §1.2 auth-param).
template <typename F>
void for_each_param(std::string_view text, F&& f) {
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == ',' || text[i] == '\t')) ++i;
    const std::size_t key_start = i;
    while (i < text.size() && text[i] != '=' && text[i] != ',') ++i;
    const std::string_view key = trim(text.substr(key_start, i - key_start));
    if (i >= text.size() || text[i] != '=') {
      continue;
    }
    ++i;
    while (i < text.size() && text[i] == ' ') ++i;
    std::string_view value;
    if (i < text.size() && text[i] == '"') {
      const std::size_t close = text.find('"', i + 1);
      const std::size_t end = close == std::string_view::npos ? text.size() : close;
      value = text.substr(i + 1, end - i - 1);
      i = end == text.size() ? end : end + 1;
    } else {
      const std::size_t start = i;
      while (i < text.size() && text[i] != ',') ++i;
      value = trim(text.substr(start, i - start));
    }
    f(key, value);
  }
}

constexpr char kBase64Alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

}  // namespace

std::string md5_hex(std::string_view data) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(data.data(), data.size(), digest, &length, EVP_md5(), nullptr);
  std::string out;
  out.reserve(length * 2);
  static constexpr char kHex[] = "0123456789abcdef";
  for (unsigned int i = 0; i < length; ++i) {
    out.push_back(kHex[digest[i] >> 4]);
    out.push_back(kHex[digest[i] & 0xF]);
  }
  return out;
}

std::string base64_encode(std::span<const std::uint8_t> data) {
  std::string out;
  out.reserve((data.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= data.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t{data[i]} << 16) | (std::uint32_t{data[i + 1]} << 8) | data[i + 2];
    out.push_back(kBase64Alphabet[(v >> 18) & 63]);
    out.push_back(kBase64Alphabet[(v >> 12) & 63]);
    out.push_back(kBase64Alphabet[(v >> 6) & 63]);
    out.push_back(kBase64Alphabet[v & 63]);
  }
  if (const std::size_t left = data.size() - i; left > 0) {
    std::uint32_t v = std::uint32_t{data[i]} << 16;
    if (left == 2) v |= std::uint32_t{data[i + 1]} << 8;
    out.push_back(kBase64Alphabet[(v >> 18) & 63]);
    out.push_back(kBase64Alphabet[(v >> 12) & 63]);
    out.push_back(left == 2 ? kBase64Alphabet[(v >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

Result<std::vector<std::uint8_t>> base64_decode(std::string_view text) {
  std::vector<std::uint8_t> out;
  out.reserve(text.size() * 3 / 4);
  std::uint32_t acc = 0;
  int bits = 0;
  bool padding = false;
  for (char c : text) {
    if (c == ' ' || c == '\r' || c == '\n' || c == '\t') continue;
    if (c == '=') {
      padding = true;
      continue;
    }
    const int v = base64_value(c);
    if (v < 0 || padding) return Error(Errc::invalid_argument, "invalid base64");
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xFF));
    }
  }
  return out;
}

std::string digest_response(std::string_view user, std::string_view realm, std::string_view password,
                            std::string_view method, std::string_view uri, std::string_view nonce,
                            std::string_view qop, std::string_view nc, std::string_view cnonce) {
  std::string a1;
  a1.append(user).append(":").append(realm).append(":").append(password);
  std::string a2;
  a2.append(method).append(":").append(uri);
  const std::string ha1 = md5_hex(a1);
  const std::string ha2 = md5_hex(a2);
  std::string k;
  k.append(ha1).append(":").append(nonce).append(":");
  if (!qop.empty()) k.append(nc).append(":").append(cnonce).append(":").append(qop).append(":");
  k.append(ha2);
  return md5_hex(k);
}

Result<AuthChallenge> parse_challenge(std::string_view value) {
  value = trim(value);
  const std::size_t sp = value.find(' ');
  const std::string_view scheme = value.substr(0, sp);
  const std::string_view params = sp == std::string_view::npos ? std::string_view() : value.substr(sp + 1);
  AuthChallenge c;
  if (iequals(scheme, "Basic")) {
    c.scheme = AuthScheme::basic;
  } else if (iequals(scheme, "Digest")) {
    c.scheme = AuthScheme::digest;
  } else {
    return Error(Errc::protocol, "unknown authentication scheme");
  }
  for_each_param(params, [&](std::string_view key, std::string_view val) {
    if (iequals(key, "realm")) c.realm = std::string(val);
    else if (iequals(key, "nonce")) c.nonce = std::string(val);
    else if (iequals(key, "opaque")) c.opaque = std::string(val);
    else if (iequals(key, "algorithm")) c.algorithm = std::string(val);
    else if (iequals(key, "stale")) c.stale = iequals(val, "true");
    else if (iequals(key, "qop")) c.qop_auth = method_listed(val, "auth");
  });
  if (c.scheme == AuthScheme::digest && c.nonce.empty()) return Error(Errc::protocol, "Digest challenge without nonce");
  return c;
}

Result<AuthChallenge> choose_challenge(std::span<const std::string_view> values) {
  std::optional<AuthChallenge> basic;
  for (std::string_view v : values) {
    auto c = parse_challenge(v);
    if (!c) continue;
    if (c->scheme == AuthScheme::digest && (c->algorithm.empty() || iequals(c->algorithm, "MD5"))) return *c;
    if (c->scheme == AuthScheme::basic && !basic) basic = *c;
  }
  if (basic) return *basic;
  return Error(Errc::not_supported, "no Basic or Digest MD5 challenge offered");
}

void Authenticator::set_challenge(AuthChallenge challenge) {
  challenge_ = std::move(challenge);
  nonce_count_ = 0;
}

std::string Authenticator::authorization(std::string_view method, std::string_view uri, std::string_view cnonce) {
  if (!active()) return {};
  if (challenge_.scheme == AuthScheme::basic) {
    std::string pair = credentials_.user + ":" + credentials_.password;
    return "Basic " + base64_encode(std::span(reinterpret_cast<const std::uint8_t*>(pair.data()), pair.size()));
  }
  std::string out = "Digest username=\"" + credentials_.user + "\", realm=\"" + challenge_.realm + "\", nonce=\"" +
                    challenge_.nonce + "\", uri=\"" + std::string(uri) + "\", response=\"";
  if (challenge_.qop_auth) {
    char nc[9];
    std::snprintf(nc, sizeof nc, "%08x", ++nonce_count_);
    out += digest_response(credentials_.user, challenge_.realm, credentials_.password, method, uri, challenge_.nonce,
                           "auth", nc, cnonce);
    out += "\", qop=auth, nc=";
    out += nc;
    out += ", cnonce=\"";
    out += cnonce;
    out += '"';
  } else {
    out += digest_response(credentials_.user, challenge_.realm, credentials_.password, method, uri, challenge_.nonce, "",
                           "", "");
    out += '"';
  }
  if (!challenge_.opaque.empty()) out += ", opaque=\"" + challenge_.opaque + "\"";
  if (!challenge_.algorithm.empty()) out += ", algorithm=" + challenge_.algorithm;
  return out;
}

}  // namespace sen3bot::camera
