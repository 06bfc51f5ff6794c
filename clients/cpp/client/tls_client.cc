#include "client/tls_client.h"

#include <openssl/err.h>
#include <openssl/ssl.h>

#include <boost/asio/ip/address.hpp>
#include <boost/asio/ssl/host_name_verification.hpp>

#include "client/robot_client.h"

namespace rmap::client {

namespace ssl = boost::asio::ssl;

std::shared_ptr<ssl::context> makeClientTlsContext(const std::string& ca_file) {
  auto context = std::make_shared<ssl::context>(ssl::context::tls_client);
  context->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                       ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
  context->set_verify_mode(ssl::verify_peer);
  boost::system::error_code ec;
  if (ca_file.empty()) {
    context->set_default_verify_paths(ec);
    if (ec) throw ClientError("cannot load the system's trusted CA certificates: " + ec.message());
  } else {
    context->load_verify_file(ca_file, ec);
    if (ec) throw ClientError("CA file '" + ca_file + "': no PEM certificate could be loaded (" + ec.message() + ")");
  }
  return context;
}

void prepareTlsStream(TlsTcpStream& stream, const std::string& host) {
  stream.set_verify_callback(ssl::host_name_verification(host));
  boost::system::error_code not_an_address;
  boost::asio::ip::make_address(host, not_an_address);
  // RFC 6066 §3: SNI carries host names only, never address literals.
  if (not_an_address && SSL_set_tlsext_host_name(stream.native_handle(), host.c_str()) != 1) {
    ERR_clear_error();
    throw ClientError("TLS: the server name '" + host + "' is not usable for SNI");
  }
}

}  // namespace rmap::client
