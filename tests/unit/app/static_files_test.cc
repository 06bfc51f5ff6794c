#include "app/static_files.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <boost/beast/http/field.hpp>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/http_api.h"
#include "service_test_support.h"

namespace rmap::app {
namespace {

namespace fs = std::filesystem;
namespace http = boost::beast::http;
using nlohmann::json;
using testing::header;

constexpr const char* kImportMap = R"({"imports":{"three":"/node_modules/three/build/three.module.js"}})";
/// SHA-256 of kImportMap in base64 (python3 hashlib), as the CSP names it.
constexpr const char* kImportMapHash = "'sha256-3J5ThQnhDolx6EqjqAMncTo9GpfA0Jp90il9IXQ4Cxk='";

void writeFile(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

/// An HttpApi with tokens configured (so the API needs one) over a web root in a temp dir:
///   <tmp>/outside/secret.txt             a file no request may reach
///   <tmp>/web/index.html                 with kImportMap inline
///   <tmp>/web/app/…                      the viewer's files, a dotfile, links in and out
///   <tmp>/web/node_modules/three/…       build/, examples/jsm/, and files outside them
class StaticFilesTest : public ::testing::Test {
 protected:
  StaticFilesTest() {
    const fs::path web = webRoot();
    writeFile(dir_.path() / "outside" / "secret.txt", "SECRET");
    writeFile(web / "secret.txt", "SECRET");  // in the web root, but not in the URL layout
    writeFile(web / "index.html", std::string("<!doctype html><html><head><script type=\"importmap\">") + kImportMap +
                                      "</script><script type=\"module\" src=\"/app/main.js\"></script></head></html>");
    writeFile(web / "app" / "main.js", "import * as THREE from 'three';\n");
    writeFile(web / "app" / "style.css", "body{}");
    writeFile(web / "app" / "img" / "logo.PNG", "\x89PNG");
    writeFile(web / "app" / "img" / "icon.svg", "<svg/>");
    writeFile(web / "app" / "data.json", "{}");
    writeFile(web / "app" / "decoder.wasm", "wasm");
    writeFile(web / "app" / "main.js.map", "{}");
    writeFile(web / "app" / "favicon.ico", "ico");
    writeFile(web / "app" / "README", "text");
    writeFile(web / "app" / ".env", "SECRET");
    writeFile(web / "app" / ".hidden" / "x.js", "SECRET");
    writeFile(web / "app" / "%2e%2e" / "literal.js", "literal");
    fs::create_symlink("../../outside/secret.txt", web / "app" / "escape.js");
    fs::create_symlink("../../outside", web / "app" / "outdir");
    fs::create_symlink("../index.html", web / "app" / "index-link.html");
    fs::create_symlink("main.js", web / "app" / "alias.js");
    const fs::path three = web / "node_modules" / "three";
    writeFile(three / "package.json", "SECRET");
    writeFile(three / "src" / "Three.js", "SECRET");
    writeFile(three / "examples" / "fonts" / "x.json", "SECRET");
    writeFile(three / "build" / "three.module.js", "export const REVISION = '170';\n");
    writeFile(three / "examples" / "jsm" / "controls" / "OrbitControls.js", "import 'three';\n");
    writeFile(web / "node_modules" / "other" / "index.js", "SECRET");
  }

  fs::path webRoot() const { return dir_.path() / "web"; }

  net::Response call(http::verb method, const std::string& target,
                     std::initializer_list<std::pair<http::field, std::string>> headers = {}) {
    net::Request request{method, target, 11};
    for (const auto& [field, value] : headers) request.set(field, value);
    return api_.handle(request, kRemote);
  }
  net::Response get(const std::string& target,
                    std::initializer_list<std::pair<http::field, std::string>> headers = {}) {
    return call(http::verb::get, target, headers);
  }

  /// Expects a JSON error with this status and code that reveals nothing of the files refused.
  void expectRefused(const std::string& target, int status, const std::string& code) {
    const net::Response response = get(target);
    EXPECT_EQ(response.result_int(), status) << target;
    EXPECT_EQ(header(response, http::field::content_type), "application/json") << target;
    EXPECT_EQ(json::parse(response.body())["error"]["code"], code) << target << ": " << response.body();
    EXPECT_EQ(response.body().find("SECRET"), std::string::npos) << target;
  }

  static Config config(const fs::path& data_dir, const fs::path& web_root) {
    Config c = testing::configIn(data_dir);
    c.web_root = web_root;
    c.auth.tokens.push_back({"viewer-token-1", Role::kViewer, ""});
    return c;
  }

  const net::Peer kRemote{"192.0.2.7", 40000, false};
  store::TempDir dir_;
  MappingService service_{config(dir_.path() / "data", webRoot())};
  Authenticator auth_{service_.config().auth};
  HttpApi api_{service_, auth_};
};

TEST_F(StaticFilesTest, ServesTheIndexAtTheRootAndAsIndexHtml) {
  std::ifstream in(webRoot() / "index.html");
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const std::string target : {"/", "/index.html", "/?token=abc", "//index.html/"}) {
    const net::Response response = get(target);
    ASSERT_EQ(response.result_int(), 200) << target << ": " << response.body();
    EXPECT_EQ(response.body(), html) << target;
    EXPECT_EQ(header(response, http::field::content_type), "text/html; charset=utf-8");
    EXPECT_EQ(header(response, http::field::cache_control), "no-cache");
    EXPECT_EQ(header(response, "X-Content-Type-Options"), "nosniff");
    EXPECT_EQ(header(response, "Content-Security-Policy"), contentSecurityPolicy(html));
    EXPECT_FALSE(header(response, http::field::etag).empty());
  }
}

TEST_F(StaticFilesTest, NeedsNoTokenWhileTheApiDoes) {
  EXPECT_EQ(get("/").result_int(), 200);
  EXPECT_EQ(get("/app/main.js").result_int(), 200);
  EXPECT_EQ(get("/node_modules/three/build/three.module.js").result_int(), 200);
  EXPECT_EQ(get("/v1/maps").result_int(), 401);
  // Outside the layout nothing is static: such paths are authenticated like any other.
  EXPECT_EQ(get("/secret.txt").result_int(), 401);
  EXPECT_EQ(get("/.git/config").result_int(), 401);
}

TEST_F(StaticFilesTest, ContentTypesFollowTheExtension) {
  const std::pair<std::string, std::string> cases[] = {
      {"/app/main.js", "text/javascript; charset=utf-8"},
      {"/app/style.css", "text/css; charset=utf-8"},
      {"/app/img/logo.PNG", "image/png"},
      {"/app/img/icon.svg", "image/svg+xml"},
      {"/app/data.json", "application/json"},
      {"/app/decoder.wasm", "application/wasm"},
      {"/app/main.js.map", "application/json"},
      {"/app/favicon.ico", "image/x-icon"},
      {"/app/README", "application/octet-stream"},
      {"/node_modules/three/build/three.module.js", "text/javascript; charset=utf-8"},
  };
  for (const auto& [target, type] : cases) {
    const net::Response response = get(target);
    ASSERT_EQ(response.result_int(), 200) << target << ": " << response.body();
    EXPECT_EQ(header(response, http::field::content_type), type) << target;
    EXPECT_EQ(header(response, http::field::cache_control), "no-cache") << target;
    EXPECT_EQ(header(response, "Content-Security-Policy"), "") << target << " is not a page";
  }
  EXPECT_EQ(contentTypeFor("a/b.MJS"), "text/javascript; charset=utf-8");
  EXPECT_EQ(contentTypeFor("page.html"), "text/html; charset=utf-8");
}

TEST_F(StaticFilesTest, ServesThreeOnlyFromBuildAndExamplesJsm) {
  const net::Response build = get("/node_modules/three/build/three.module.js");
  ASSERT_EQ(build.result_int(), 200);
  EXPECT_EQ(build.body(), "export const REVISION = '170';\n");
  const net::Response addon = get("/node_modules/three/examples/jsm/controls/OrbitControls.js");
  ASSERT_EQ(addon.result_int(), 200);
  EXPECT_EQ(addon.body(), "import 'three';\n");
  for (const std::string target :
       {"/node_modules/three/package.json", "/node_modules/three/src/Three.js",
        "/node_modules/three/examples/fonts/x.json", "/node_modules/other/index.js", "/node_modules/three/build",
        "/node_modules/three/build/", "/node_modules/three/examples/jsm", "/node_modules/three", "/node_modules",
        "/node_modules/three/build/missing.js"}) {
    expectRefused(target, 404, "not_found");
  }
}

TEST_F(StaticFilesTest, TraversalAttemptsAreRefused) {
  for (const std::string target :
       {"/app/../../outside/secret.txt", "/app/../secret.txt", "/app/./main.js", "/app/..",
        "/app/%2e%2e/%2e%2e/outside/secret.txt", "/app/%2E%2E/secret.txt", "/app/.%2e/secret.txt",
        "/node_modules/three/build/../../../secret.txt", "/node_modules/three/examples/jsm/../../build/three.module.js",
        "/app/..%2f..%2foutside%2fsecret.txt", "/app/img%2Flogo.PNG", "/app/main.js%00.png", "/app/%00",
        "/app/..%5c..%5csecret.txt%00"}) {
    expectRefused(target, 400, "invalid_argument");
  }
  expectRefused("/app/%zz", 400, "invalid_argument");  // malformed percent-encoding
  // Decoded once: %252e%252e is the literal name "%2e%2e", a directory like any other.
  const net::Response literal = get("/app/%252e%252e/literal.js");
  EXPECT_EQ(literal.result_int(), 200);
  EXPECT_EQ(literal.body(), "literal");
  expectRefused("/app/%252e%252e/%252e%252e/secret.txt", 404, "not_found");
}

TEST_F(StaticFilesTest, SymlinksMayNotLeaveTheirDirectory) {
  expectRefused("/app/escape.js", 404, "not_found");
  expectRefused("/app/outdir/secret.txt", 404, "not_found");
  expectRefused("/app/index-link.html", 404, "not_found");  // into the web root, but out of app/
  const net::Response alias = get("/app/alias.js");
  EXPECT_EQ(alias.result_int(), 200);
  EXPECT_EQ(alias.body(), "import * as THREE from 'three';\n");
}

TEST_F(StaticFilesTest, DotfilesDirectoriesAndOtherFilesAreNotServed) {
  for (const std::string target : {"/app/.env", "/app/.hidden/x.js", "/app/img", "/app/img/", "/app", "/app/",
                                   "/app/missing.js", "/app/main.js/x"}) {
    expectRefused(target, 404, "not_found");
  }
  // A FIFO would block a plain open(); it is answered at once and not served.
  ASSERT_EQ(::mkfifo((webRoot() / "app" / "pipe.js").c_str(), 0600), 0);
  expectRefused("/app/pipe.js", 404, "not_found");
}

TEST_F(StaticFilesTest, AMatchingETagAnswers304UntilTheFileChanges) {
  const net::Response first = get("/app/main.js");
  const std::string etag = header(first, http::field::etag);
  ASSERT_FALSE(etag.empty());
  EXPECT_EQ(etag.front(), '"');
  for (const std::string& validator : {etag, "W/" + etag, "\"other\", " + etag, std::string("*")}) {
    const net::Response again = get("/app/main.js", {{http::field::if_none_match, validator}});
    EXPECT_EQ(again.result_int(), 304) << validator;
    EXPECT_EQ(again.body(), "") << validator;
    EXPECT_EQ(header(again, http::field::etag), etag) << validator;
    EXPECT_EQ(header(again, http::field::cache_control), "no-cache") << validator;
  }
  EXPECT_EQ(get("/app/main.js", {{http::field::if_none_match, "\"other\""}}).result_int(), 200);

  writeFile(webRoot() / "app" / "main.js", "import * as THREE from 'three'; // changed\n");
  const net::Response changed = get("/app/main.js", {{http::field::if_none_match, etag}});
  EXPECT_EQ(changed.result_int(), 200);
  EXPECT_NE(header(changed, http::field::etag), etag);
  EXPECT_EQ(changed.body(), "import * as THREE from 'three'; // changed\n");
}

TEST_F(StaticFilesTest, HeadSendsTheHeadersOfGetWithoutTheBody) {
  for (const std::string target : {"/", "/app/style.css", "/node_modules/three/build/three.module.js"}) {
    const net::Response full = get(target);
    const net::Response head = call(http::verb::head, target);
    ASSERT_EQ(head.result_int(), 200) << target;
    EXPECT_EQ(head.body(), "") << target;
    EXPECT_EQ(header(head, http::field::content_length), std::to_string(full.body().size())) << target;
    for (const http::field field : {http::field::content_type, http::field::etag, http::field::cache_control}) {
      EXPECT_EQ(header(head, field), header(full, field)) << target;
    }
    EXPECT_EQ(header(head, "Content-Security-Policy"), header(full, "Content-Security-Policy")) << target;
  }
  // Errors to HEAD have no body either, or a kept-alive connection would lose its framing.
  const net::Response missing = call(http::verb::head, "/app/missing.js");
  EXPECT_EQ(missing.result_int(), 404);
  EXPECT_EQ(missing.body(), "");
  EXPECT_NE(header(missing, http::field::content_length), "0");
}

TEST_F(StaticFilesTest, OtherMethodsGet405WithAllow) {
  for (const auto& [method, target] : {std::pair{http::verb::post, "/"}, {http::verb::put, "/index.html"},
                                       {http::verb::delete_, "/app/main.js"},
                                       {http::verb::post, "/node_modules/three/build/three.module.js"},
                                       {http::verb::options, "/app/missing.js"}}) {
    const net::Response response = call(method, target);
    EXPECT_EQ(response.result_int(), 405) << target;
    EXPECT_EQ(header(response, http::field::allow), "GET, HEAD") << target;
    EXPECT_EQ(json::parse(response.body())["error"]["code"], "method_not_allowed") << target;
  }
  std::ifstream in(webRoot() / "app" / "main.js");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "import * as THREE from 'three';\n");
}

/// A viewer that is not installed: the index says how to install it, the API keeps working.
class MissingViewerTest : public ::testing::Test {
 protected:
  net::Response get(const fs::path& web_root, const std::string& target) {
    Config config = testing::configIn(dir_.path() / "data");
    config.web_root = web_root;
    MappingService service(config);
    const Authenticator auth(config.auth);
    HttpApi api(service, auth);
    net::Request request{http::verb::get, target, 11};
    return api.handle(request, net::Peer{"127.0.0.1", 40000, true});
  }
  void expectNotInstalled(const fs::path& web_root) {
    for (const std::string target : {"/", "/index.html"}) {
      const net::Response response = get(web_root, target);
      EXPECT_EQ(response.result_int(), 503) << target;
      const json body = json::parse(response.body());
      EXPECT_EQ(body["error"]["code"], "viewer_not_installed");
      EXPECT_NE(body["error"]["message"].get<std::string>().find("npm ci --prefix web"), std::string::npos);
      EXPECT_EQ(response.body().find(dir_.path().string()), std::string::npos) << "paths stay in the log";
    }
    EXPECT_EQ(get(web_root, "/healthz").result_int(), 200);
    EXPECT_EQ(get(web_root, "/v1/maps").result_int(), 200);
  }

  store::TempDir dir_;
};

TEST_F(MissingViewerTest, NoWebRoot) {
  const fs::path web = dir_.path() / "no-such-dir";
  EXPECT_EQ(missingViewerFile(web), web / "index.html");
  expectNotInstalled(web);
  EXPECT_EQ(get(web, "/app/main.js").result_int(), 404);
}

TEST_F(MissingViewerTest, NoIndex) {
  const fs::path web = dir_.path() / "web";
  writeFile(web / "node_modules" / "three" / "build" / "three.module.js", "");
  EXPECT_EQ(missingViewerFile(web), web / "index.html");
  expectNotInstalled(web);
}

TEST_F(MissingViewerTest, IndexWithoutThree) {
  // A source tree before `npm ci`: the page is there, the library it imports is not.
  const fs::path web = dir_.path() / "web";
  writeFile(web / "index.html", "<!doctype html>");
  writeFile(web / "app" / "main.js", "");
  EXPECT_EQ(missingViewerFile(web), web / "node_modules/three/build/three.module.js");
  expectNotInstalled(web);
  EXPECT_EQ(get(web, "/app/main.js").result_int(), 200);
  writeFile(web / "node_modules" / "three" / "build" / "three.module.js", "");
  EXPECT_EQ(missingViewerFile(web), std::nullopt);
  EXPECT_EQ(get(web, "/").result_int(), 200) << "installing needs no restart";
}

std::string scriptSources(const std::string& html) {
  const std::string csp = contentSecurityPolicy(html);
  const size_t start = csp.find("script-src ");
  return csp.substr(start + 11, csp.find(';', start) - start - 11);
}

TEST(ContentSecurityPolicy, KeepsEverythingOnThisServer) {
  const std::string csp = contentSecurityPolicy("<!doctype html>");
  for (const char* directive : {"default-src 'self'", "script-src 'self';", "connect-src 'self'",
                                "img-src 'self' data: blob:", "style-src 'self' 'unsafe-inline'",
                                "object-src 'none'", "base-uri 'none'", "frame-ancestors 'none'"}) {
    EXPECT_NE(csp.find(directive), std::string::npos) << directive << " in " << csp;
  }
  EXPECT_EQ(csp.find("unsafe-eval"), std::string::npos);
  EXPECT_EQ(scriptSources("<!doctype html>"), "'self'");
}

TEST(ContentSecurityPolicy, AllowsTheImportMapByItsHashOnly) {
  const std::string map = kImportMap;
  EXPECT_EQ(scriptSources("<script type=\"importmap\">" + map + "</script>"), std::string("'self' ") + kImportMapHash);
  // Attributes as HTML reads them: any case, quoted or not, in any order, spaces around '='.
  for (const std::string tag : {"<script type=importmap>", "<SCRIPT TYPE='ImportMap'>",
                                "<script nonce=\"x\" type = \" importmap \" data-x=\"a>b\">",
                                "<script\ntype=\"importmap\"\n>"}) {
    EXPECT_EQ(scriptSources("<head>" + tag + map + "</ScRiPt ></head>"), std::string("'self' ") + kImportMapHash)
        << tag;
  }
  // The browser reads CRLF and CR as LF before it hashes.
  EXPECT_EQ(scriptSources("<script type=\"importmap\">\r\n  {\"imports\": {}}\r</script>"),
            "'self' 'sha256-pFEsPcv7ljCd04KxGPDV1BI1joHi4wL6EX606Bn7x5U='");
  // Other scripts get nothing: they must be files under /app/.
  EXPECT_EQ(scriptSources("<script type=\"module\">alert(1)</script><script>alert(2)</script>"
                          "<scripts type=\"importmap\">{}</scripts><script type=\"importmapx\">{}</script>"
                          "<script type=\"module\" src=\"/app/main.js\"></script>"),
            "'self'");
  // The first type attribute counts, as in HTML.
  EXPECT_EQ(scriptSources("<script type=\"module\" type=\"importmap\">{}</script>"), "'self'");
  // Each import map is hashed; "</script" must end with a space, '/' or '>' to close one.
  EXPECT_EQ(scriptSources("<script type=importmap>{}</script><script type=importmap>" + map + "</script>"),
            std::string("'self' 'sha256-RBNvo1WzZ4oRRq0W9+hknpT7T8If536DEMBg9hyq/4o=' ") + kImportMapHash);
  EXPECT_EQ(scriptSources("<script type=\"importmap\">" + map), std::string("'self' ") + kImportMapHash);
  EXPECT_EQ(scriptSources("<script type=\"importmap"), "'self'");
}

}  // namespace
}  // namespace rmap::app
