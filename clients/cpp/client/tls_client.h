#pragma once
/// @file tls_client.h
/// TLS for the clients (https://, wss://): a context that verifies the
/// server, and the per-connection checks of its name.

#include <boost/asio/ssl/context.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/ssl/ssl_stream.hpp>
#include <memory>
#include <string>

namespace rmap::client {

using TlsTcpStream = boost::beast::ssl_stream<boost::beast::tcp_stream>;

/// A TLS 1.2+ client context that verifies the server's certificate chain
/// against the PEM certificates in `ca_file`, or against the system's default
/// trust store when `ca_file` is empty.
/// @throws ClientError when `ca_file` cannot be read or holds no certificate
std::shared_ptr<boost::asio::ssl::context> makeClientTlsContext(const std::string& ca_file);

/// Before the handshake on `stream`: the certificate must name `host` (a DNS
/// name, or an IP address in its subjectAltName), and host names (not
/// addresses) are sent as SNI.
/// @throws ClientError when OpenSSL refuses the name
void prepareTlsStream(TlsTcpStream& stream, const std::string& host);

}  // namespace rmap::client
