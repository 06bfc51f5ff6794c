#pragma once
/// @file rmapd_service.h
/// rmapd as the network layer sees it: HTTP requests go to the HttpApi,
/// WebSocket upgrades become robot or viewer sessions after authentication
/// and the Origin check.

#include "app/auth.h"
#include "app/http_api.h"
#include "app/mapping_service.h"
#include "net/service.h"

namespace rmap::app {

class RmapdService : public net::Service {
 public:
  explicit RmapdService(MappingService& service);

  net::Response handleHttp(net::Request& request, const net::Peer& peer) override;
  net::WsAccept acceptWebSocket(const net::Request& request, const net::Peer& peer) override;

 private:
  MappingService& service_;
  Authenticator auth_;
  HttpApi api_;
};

}  // namespace rmap::app
