#pragma once
/// @file header_checks.h
/// The checks of a request header that Beast's parser lets through but rmapd
/// refuses before it reads the body; pure, so that the HTTP session and the
/// fuzz target (tests/fuzz/http_request_fuzz.cc) share them.

#include <optional>

#include "net/service.h"

namespace rmap::net {

/// Why a request whose header parsed cannot be served, as the error that
/// answers it (the connection then closes), or nullopt.
/// - Host: HTTP/1.1 requires exactly one, and no version allows two
///   (RFC 9112 §3.2).
/// - Transfer-Encoding: a body length that two parties may judge differently
///   is how requests are smuggled past a proxy. Beast rejects it next to a
///   Content-Length, but takes a request whose last coding is not chunked
///   as having no body, so its body would be read as the next request
///   (RFC 9112 §6.1 asks for a 400); HTTP/1.0 has no Transfer-Encoding; and
///   only chunked is decoded, so other codings get 501 rather than reaching
///   the Service still encoded.
/// - Expect: only 100-continue is known (RFC 9110 §10.1.1); HTTP/1.0 servers
///   ignore the field.
/// @param chunked  whether the parser took the body as chunked (parser::chunked())
std::optional<Response> headerError(const Request& request, bool chunked);

}  // namespace rmap::net
