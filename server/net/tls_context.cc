#include "net/tls_context.h"

#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

namespace rmap::net {
namespace {

namespace ssl = boost::asio::ssl;

/// Opening the file first gives "No such file or directory" or "Permission
/// denied" instead of OpenSSL's less direct "system lib" error.
void requireReadable(const std::filesystem::path& file, const std::string& what) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(what + " " + file.string() + " cannot be read: " + std::strerror(errno));
}

/// The error OpenSSL queued last (the queue is emptied).
unsigned long lastOpenSslError() {
  unsigned long code = 0;
  unsigned long last = 0;
  while ((code = ERR_get_error()) != 0) last = code;
  return last;
}

/// Its reason, e.g. "no start line".
std::string reasonOf(unsigned long error) {
  const char* reason = error != 0 ? ERR_reason_error_string(error) : nullptr;
  return reason ? reason : "unknown OpenSSL error";
}

}  // namespace

std::shared_ptr<ssl::context> makeServerTlsContext(const std::filesystem::path& certificate_file,
                                                   const std::filesystem::path& private_key_file) {
  requireReadable(certificate_file, "certificate file");
  requireReadable(private_key_file, "private key file");
  auto context = std::make_shared<ssl::context>(ssl::context::tls_server);
  context->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                       ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1 | ssl::context::single_dh_use);
  SSL_CTX* native = context->native_handle();
  ERR_clear_error();
  const auto mismatch = [&] {
    return std::runtime_error("private key file " + private_key_file.string() + " does not belong to certificate " +
                              certificate_file.string());
  };
  if (SSL_CTX_use_certificate_chain_file(native, certificate_file.c_str()) != 1) {
    throw std::runtime_error("certificate file " + certificate_file.string() +
                             " holds no PEM certificate: " + reasonOf(lastOpenSslError()));
  }
  if (SSL_CTX_use_PrivateKey_file(native, private_key_file.c_str(), SSL_FILETYPE_PEM) != 1) {
    const unsigned long error = lastOpenSslError();
    if (ERR_GET_LIB(error) == ERR_LIB_X509 && ERR_GET_REASON(error) == X509_R_KEY_VALUES_MISMATCH) throw mismatch();
    throw std::runtime_error("private key file " + private_key_file.string() +
                             " holds no unencrypted PEM private key: " + reasonOf(error));
  }
  if (SSL_CTX_check_private_key(native) != 1) {
    lastOpenSslError();
    throw mismatch();
  }
  return context;
}

}  // namespace rmap::net
