// Endpoint::parse: the URL shapes the clients accept.

#include <algorithm>
#include <cctype>
#include <charconv>

#include "client/robot_client.h"

namespace rmap::client {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

Endpoint Endpoint::parse(const std::string& url) {
  const auto bad = [&url](const std::string& why) { return ClientError("bad URL '" + url + "': " + why); };
  if (std::any_of(url.begin(), url.end(), [](unsigned char c) { return c <= ' ' || c == 0x7f; })) {
    throw bad("contains whitespace or control characters");
  }
  const size_t scheme_end = url.find("://");
  if (scheme_end == std::string::npos) {
    throw bad("expected ws[s]://host:port[/path] or http[s]://host:port[/path]");
  }
  const std::string scheme = lower(url.substr(0, scheme_end));
  if (scheme != "ws" && scheme != "http" && scheme != "wss" && scheme != "https") {
    throw bad("unknown scheme '" + scheme + "'");
  }

  const size_t authority_begin = scheme_end + 3;
  const size_t path_begin = std::min(url.find_first_of("/?#", authority_begin), url.size());
  const std::string authority = url.substr(authority_begin, path_begin - authority_begin);
  if (authority.find('@') != std::string::npos) throw bad("user info is not supported");

  Endpoint e;
  e.tls = scheme == "wss" || scheme == "https";
  std::string port;
  if (!authority.empty() && authority.front() == '[') {  // [IPv6 literal]
    const size_t close = authority.find(']');
    if (close == std::string::npos) throw bad("unterminated '['");
    e.host = authority.substr(1, close - 1);
    const std::string rest = authority.substr(close + 1);
    if (!rest.empty()) {
      if (rest.front() != ':') throw bad("expected ':' after ']'");
      port = rest.substr(1);
      if (port.empty()) throw bad("empty port");
    }
  } else {
    const size_t colon = authority.find(':');
    e.host = authority.substr(0, colon);
    if (colon != std::string::npos) {
      port = authority.substr(colon + 1);
      if (port.empty()) throw bad("empty port");
    }
  }
  if (e.host.empty()) throw bad("missing host");
  // Without a port the scheme's default applies.
  if (port.empty()) port = e.tls ? "443" : "80";
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (ec != std::errc() || end != port.data() + port.size() || value == 0 || value > 65535) {
    throw bad("port must be a number in [1, 65535]");
  }
  e.port = port;

  if (path_begin < url.size() && url[path_begin] == '#') throw bad("fragments are not supported");
  e.path = url.substr(path_begin);
  if (e.path.empty() || e.path.front() != '/') e.path = "/" + e.path;  // "?q" alone means "/?q"
  if (e.path.find('#') != std::string::npos) throw bad("fragments are not supported");
  return e;
}

}  // namespace rmap::client
