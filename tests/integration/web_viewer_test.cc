// The web viewer's files over a real connection: rmapd started with --web-root
// serves the page, its modules and three without a token while the API keeps
// asking for one; HEAD keeps a kept-alive connection framed; a missing viewer
// is a 503 that says how to install it, and a warning at start-up.
#include <gtest/gtest.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <fstream>

#include "api_helpers.h"
#include "client/http_client.h"
#include "rmapd_process.h"

namespace rmap::testing {
namespace {

namespace fs = std::filesystem;
namespace beast = boost::beast;
namespace http = beast::http;

constexpr const char* kViewerConfig = R"(
auth:
  tokens:
    - {token: viewer-token-1, role: viewer}
)";

constexpr const char* kIndex = R"(<!doctype html>
<html><head><meta charset="utf-8"><title>rmap</title>
<script type="importmap">{"imports":{"three":"/node_modules/three/build/three.module.js","three/addons/":"/node_modules/three/examples/jsm/"}}</script>
<script type="module" src="/app/main.js"></script></head><body></body></html>
)";

class WebViewer : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path web = dir_.path() / "web";
    writeFile(web / "index.html", kIndex);
    writeFile(web / "app" / "main.js", "import * as THREE from 'three';\n");
    // As large as three's real module build (about 1.3 MB), so a body spans many socket writes.
    three_.assign(1'300'000, 'x');
    for (size_t i = 0; i < three_.size(); i += 64) three_[i] = '\n';
    writeFile(web / "node_modules" / "three" / "build" / "three.module.js", three_);
    writeFile(web / "node_modules" / "three" / "examples" / "jsm" / "controls" / "OrbitControls.js",
              "import { EventDispatcher } from 'three';\n");
    rmapd_ = std::make_unique<RmapdProcess>(dir_.path() / "data", kViewerConfig, std::chrono::seconds(60),
                                            std::vector<std::string>{"--web-root", web.string()});
  }

  TempDir dir_{"rmap-web-viewer"};
  std::string three_;
  std::unique_ptr<RmapdProcess> rmapd_;
};

TEST_F(WebViewer, ServesThePageItsModulesAndThreeWithoutAToken) {
  client::HttpClient http(rmapd_->httpUrl());
  const client::HttpResponse page = http.get("/");
  ASSERT_EQ(page.status, 200) << page.body;
  EXPECT_EQ(page.body, kIndex);
  EXPECT_EQ(page.header("content-type"), "text/html; charset=utf-8");
  EXPECT_EQ(page.header("cache-control"), "no-cache");
  const std::string csp = page.header("content-security-policy");
  EXPECT_NE(csp.find("default-src 'self'"), std::string::npos) << csp;
  EXPECT_NE(csp.find("script-src 'self' 'sha256-"), std::string::npos) << "the import map is allowed by hash: " << csp;

  const client::HttpResponse main = http.get("/app/main.js");
  ASSERT_EQ(main.status, 200) << main.body;
  EXPECT_EQ(main.body, "import * as THREE from 'three';\n");
  EXPECT_EQ(main.header("content-type"), "text/javascript; charset=utf-8");

  const client::HttpResponse three = http.get("/node_modules/three/build/three.module.js");
  ASSERT_EQ(three.status, 200);
  EXPECT_EQ(three.body, three_);
  const client::HttpResponse addon = http.get("/node_modules/three/examples/jsm/controls/OrbitControls.js");
  EXPECT_EQ(addon.status, 200);

  // A reload revalidates: the same file answers 304 without a body.
  const client::HttpResponse again =
      http.get("/node_modules/three/build/three.module.js", {{"If-None-Match", three.header("etag")}});
  EXPECT_EQ(again.status, 304);
  EXPECT_TRUE(again.body.empty());

  EXPECT_EQ(http.get("/app/%2e%2e/%2e%2e/data/rmap.db").status, 400);
  EXPECT_EQ(http.get("/node_modules/three/package.json").status, 404);
  EXPECT_EQ(http.get("/v1/maps").status, 401);
  client::HttpClient viewer(rmapd_->httpUrl(), "viewer-token-1");
  EXPECT_EQ(viewer.get("/v1/maps").status, 200);
}

TEST_F(WebViewer, HeadKeepsAKeptAliveConnectionFramed) {
  boost::asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(boost::asio::ip::tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), rmapd_->port()));
  stream.expires_after(std::chrono::seconds(10));
  beast::flat_buffer buffer;
  const auto request = [&](http::verb method, const std::string& target) {
    http::request<http::empty_body> out{method, target, 11};
    out.set(http::field::host, "127.0.0.1");
    http::write(stream, out);
    http::response_parser<http::string_body> parser;
    parser.body_limit(16u << 20);
    parser.skip(method == http::verb::head);  // a HEAD answer has a length but no body
    http::read(stream, buffer, parser);
    return parser.release();
  };
  for (const std::string target : {"/node_modules/three/build/three.module.js", "/app/missing.js"}) {
    const auto head = request(http::verb::head, target);
    EXPECT_TRUE(head.body().empty()) << target;
    EXPECT_TRUE(head.keep_alive()) << target;
    const auto get = request(http::verb::get, target);
    EXPECT_EQ(head.result(), get.result()) << target;
    EXPECT_EQ(head[http::field::content_length], std::to_string(get.body().size())) << target;
  }
  const auto health = request(http::verb::get, "/healthz");
  EXPECT_EQ(health.result(), http::status::ok);
  EXPECT_EQ(nlohmann::json::parse(health.body())["status"], "ok");
}

TEST(WebViewerMissing, RootSaysHowToInstallItAndTheApiWorks) {
  TempDir dir("rmap-web-missing");
  RmapdProcess rmapd(dir.path() / "data", "", std::chrono::seconds(60),
                     {"--web-root", (dir.path() / "no-viewer").string()});
  EXPECT_NE(rmapd.log().find("web viewer not installed"), std::string::npos) << rmapd.log();
  client::HttpClient http(rmapd.httpUrl());
  const client::HttpResponse page = http.get("/");
  EXPECT_EQ(page.status, 503);
  const nlohmann::json error = nlohmann::json::parse(page.body)["error"];
  EXPECT_EQ(error["code"], "viewer_not_installed");
  EXPECT_NE(error["message"].get<std::string>().find("npm ci --prefix web"), std::string::npos) << error;
  EXPECT_EQ(http.get("/healthz").status, 200);
  EXPECT_EQ(http.get("/v1/maps").status, 200);
}

}  // namespace
}  // namespace rmap::testing
