#pragma once
/// @file http_client.h
/// A blocking HTTP/1.1 client on one keep-alive connection (reconnects when
/// the server closed it), plain (http://) or TLS (https://). For tools,
/// tests and benchmarks.

#include <chrono>
#include <map>
#include <memory>
#include <string>

namespace rmap::client {

struct HttpResponse {
  int status = 0;
  std::string body;
  std::map<std::string, std::string> headers;  ///< lower-case names
  std::string header(const std::string& lower_name) const;
};

class HttpClient {
 public:
  /// @param base_url  http://host:port or https://host:port
  /// @param ca_file   https:// only: PEM CA certificates the server's certificate
  ///                  must chain to (empty: the system's trust store); it must
  ///                  also name the URL's host
  /// @throws ClientError for a bad URL or an unreadable CA file
  explicit HttpClient(const std::string& base_url, std::string token = {},
                      std::chrono::milliseconds timeout = std::chrono::milliseconds(10000),
                      const std::string& ca_file = {});
  ~HttpClient();
  HttpClient(const HttpClient&) = delete;
  HttpClient& operator=(const HttpClient&) = delete;

  /// @param target   path and query, e.g. "/v1/maps"
  /// @param headers  extra request headers
  /// @throws ClientError on connection failure or timeout (HTTP errors are returned)
  HttpResponse get(const std::string& target, const std::map<std::string, std::string>& headers = {});
  HttpResponse post(const std::string& target, const std::string& body, const std::string& content_type,
                    const std::map<std::string, std::string>& headers = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rmap::client
