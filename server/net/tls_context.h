#pragma once
/// @file tls_context.h
/// The server side of TLS: the OpenSSL context every TLS connection of a
/// Server shares (ServerOptions::tls), built from PEM files.

#include <boost/asio/ssl/context.hpp>
#include <filesystem>
#include <memory>

namespace rmap::net {

/// A TLS 1.2+ server context holding `certificate_file` (PEM: the server's
/// certificate, then any intermediates) and `private_key_file` (PEM,
/// unencrypted).
/// @throws std::runtime_error naming the file and what is wrong with it:
///         missing or unreadable, not PEM of the expected kind, or a key that
///         does not belong to the certificate
std::shared_ptr<boost::asio::ssl::context> makeServerTlsContext(const std::filesystem::path& certificate_file,
                                                                const std::filesystem::path& private_key_file);

}  // namespace rmap::net
