#include "net/header_checks.h"

#include <boost/beast/core/string.hpp>
#include <boost/beast/http/rfc7230.hpp>
#include <iterator>

#include "net/json_error.h"

namespace rmap::net {

namespace beast = boost::beast;
namespace http = beast::http;

std::optional<Response> headerError(const Request& request, bool chunked) {
  const unsigned version = request.version();
  const size_t hosts = request.count(http::field::host);
  if (hosts > 1 || (hosts == 0 && version >= 11)) {
    return jsonError(http::status::bad_request, "bad_request", "an HTTP/1.1 request needs exactly one Host field",
                     version);
  }
  if (const size_t codings = request.count(http::field::transfer_encoding); codings > 0) {
    if (version < 11 || !chunked) {
      return jsonError(http::status::bad_request, "bad_request",
                       "Transfer-Encoding needs HTTP/1.1 and chunked as the last coding", version);
    }
    const http::token_list list{request[http::field::transfer_encoding]};
    if (codings > 1 || std::next(list.begin()) != list.end()) {
      return jsonError(http::status::not_implemented, "not_implemented", "the only transfer coding served is chunked",
                       version);
    }
  }
  const auto expect = request.find(http::field::expect);
  if (version >= 11 && expect != request.end() && !beast::iequals(expect->value(), "100-continue")) {
    return jsonError(http::status::expectation_failed, "expectation_failed", "only 100-continue is supported",
                     version);
  }
  return std::nullopt;
}

}  // namespace rmap::net
