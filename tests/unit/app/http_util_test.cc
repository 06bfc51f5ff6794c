#include "app/http_util.h"

#include <gtest/gtest.h>

#include <boost/beast/http/field.hpp>

namespace rmap::app {
namespace {

namespace http = boost::beast::http;

/// The ApiError `fn` throws; fails the test when it throws nothing.
template <typename Fn>
ApiError apiError(Fn fn) {
  try {
    fn();
  } catch (const ApiError& e) {
    return e;
  }
  ADD_FAILURE() << "no ApiError";
  return ApiError(0, "", "");
}

void expectBadParameter(const ApiError& e, const std::string& name) {
  EXPECT_EQ(e.status(), 400);
  EXPECT_EQ(e.code(), "invalid_argument");
  EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
}

TEST(TargetParse, SplitsPathSegments) {
  const Target t = Target::parse("/v1/maps//lab/tiles/0/-1/2/3/");
  EXPECT_EQ(t.segments, (std::vector<std::string>{"v1", "maps", "lab", "tiles", "0", "-1", "2", "3"}));
  EXPECT_TRUE(t.query.empty());
  EXPECT_TRUE(Target::parse("/").segments.empty());
}

TEST(TargetParse, SplitsQueryParameters) {
  const Target t = Target::parse("/v1/maps/lab/occupancy?x=1.5&y=-2&flag&=empty-key&x2=a=b");
  EXPECT_EQ(t.segments, (std::vector<std::string>{"v1", "maps", "lab", "occupancy"}));
  EXPECT_EQ(t.query, (std::map<std::string, std::string>{
                         {"x", "1.5"}, {"y", "-2"}, {"flag", ""}, {"", "empty-key"}, {"x2", "a=b"}}));
  EXPECT_TRUE(t.has("flag"));
  EXPECT_FALSE(t.has("z"));
  EXPECT_EQ(t.text("y"), "-2");
  EXPECT_EQ(t.text("z", "fallback"), "fallback");
}

TEST(TargetParse, PercentDecodesSegmentsAndQuery) {
  const Target t = Target::parse("/v1/maps/my%20map/a%2Fb?na%6De=v%C3%A9%3D");
  EXPECT_EQ(t.segments, (std::vector<std::string>{"v1", "maps", "my map", "a/b"}));
  EXPECT_EQ(t.text("name"), "v\xC3\xA9=");
}

TEST(TargetParse, PlusIsASpaceInTheQueryOnly) {
  const Target t = Target::parse("/a+b?q=c+d&e%2Bf=%2B");
  EXPECT_EQ(t.segments, std::vector<std::string>{"a+b"});
  EXPECT_EQ(t.text("q"), "c d");
  EXPECT_EQ(t.text("e+f"), "+");
}

TEST(TargetParse, BadPercentEncodingIs400) {
  for (const std::string target : {"/a%zz", "/a%4", "/a%", "/a?x=%g1", "/a?x=1%"}) {
    const ApiError e = apiError([&] { Target::parse(target); });
    EXPECT_EQ(e.status(), 400) << target;
    EXPECT_EQ(e.code(), "invalid_argument") << target;
  }
}

TEST(TargetNumber, ParsesFiniteNumbers) {
  const Target t = Target::parse("/?a=1.25&b=-3e2&c=7");
  EXPECT_EQ(t.number("a"), 1.25);
  EXPECT_EQ(t.number("b"), -300.0);
  EXPECT_EQ(t.number("c"), 7.0);
}

TEST(TargetNumber, ErrorsNameTheParameter) {
  const Target t = Target::parse("/?alpha=x&beta=inf&gamma=nan&delta=1.5m&eps=");
  for (const std::string key : {"alpha", "beta", "gamma", "delta", "eps", "missing"}) {
    expectBadParameter(apiError([&] { t.number(key); }), key);
  }
}

TEST(TargetInteger, ParsesWithinBoundsOrFallsBack) {
  const Target t = Target::parse("/?level=3&neg=-5");
  EXPECT_EQ(t.integer("level", 0, 0, 6), 3);
  EXPECT_EQ(t.integer("neg", 0, -10, 10), -5);
  EXPECT_EQ(t.integer("absent", 42, 0, 6), 42);
}

TEST(TargetInteger, ErrorsNameTheParameter) {
  const Target t = Target::parse("/?level=7&limit=abc&page=1.5");
  expectBadParameter(apiError([&] { t.integer("level", 0, 0, 6); }), "level");
  expectBadParameter(apiError([&] { t.integer("limit", 0, 0, 100); }), "limit");
  expectBadParameter(apiError([&] { t.integer("page", 0, 0, 100); }), "page");
}

TEST(TargetVector3, ParsesThreeNumbers) {
  const Target t = Target::parse("/?p=1,-2.5,3e1");
  const std::array<double, 3> expected{1.0, -2.5, 30.0};
  EXPECT_EQ(t.vector3("p"), expected);
}

TEST(TargetVector3, ErrorsNameTheParameter) {
  const Target t = Target::parse("/?two=1,2&four=1,2,3,4&gap=1,,3&word=1,2,z&nan=1,2,nan&trail=1,2,3,");
  for (const std::string key : {"two", "four", "gap", "word", "nan", "trail", "missing"}) {
    expectBadParameter(apiError([&] { t.vector3(key); }), key);
  }
}

TEST(ParseInteger, ParsesDecimalIntegers) {
  EXPECT_EQ(parseInteger("0", "n"), 0);
  EXPECT_EQ(parseInteger("-17", "n"), -17);
  EXPECT_EQ(parseInteger("9223372036854775807", "n"), INT64_MAX);
}

TEST(ParseInteger, ErrorsNameWhat) {
  for (const std::string bad : {"", "x", "1x", " 1", "1.0", "99999999999999999999", "0x10"}) {
    expectBadParameter(apiError([&] { parseInteger(bad, "tile level"); }), "tile level");
  }
}

TEST(JsonResponse, SetsStatusTypeBodyAndKeepAlive) {
  net::Request request{http::verb::get, "/", 11};
  request.keep_alive(true);
  const net::Response response = jsonResponse(request, {{"ok", true}}, 201);
  EXPECT_EQ(response.result_int(), 201u);
  EXPECT_EQ(response[http::field::content_type], "application/json");
  EXPECT_EQ(nlohmann::json::parse(response.body()), (nlohmann::json{{"ok", true}}));
  EXPECT_EQ(response[http::field::content_length], std::to_string(response.body().size()));
  EXPECT_EQ(response.version(), 11u);
  EXPECT_TRUE(response.keep_alive());
}

TEST(JsonResponse, FollowsTheRequestsKeepAlive) {
  net::Request request{http::verb::get, "/", 11};
  request.keep_alive(false);
  const net::Response response = jsonResponse(request, nlohmann::json::array());
  EXPECT_EQ(response.result_int(), 200u);
  EXPECT_FALSE(response.keep_alive());
}

TEST(AcceptsJson, LooksForApplicationJson) {
  net::Request request{http::verb::get, "/", 11};
  EXPECT_FALSE(acceptsJson(request));
  request.set(http::field::accept, "text/html");
  EXPECT_FALSE(acceptsJson(request));
  request.set(http::field::accept, "text/html, application/json;q=0.9");
  EXPECT_TRUE(acceptsJson(request));
  request.set(http::field::accept, "application/json");
  EXPECT_TRUE(acceptsJson(request));
}

TEST(EtagMatches, ReadsIfNoneMatchAsAListComparedWeakly) {
  const std::string etag = "\"7-812j\"";
  net::Request request{http::verb::get, "/", 11};
  EXPECT_FALSE(etagMatches(request, etag));
  for (const std::string value : {"\"7-812j\"", "W/\"7-812j\"", "\"1-1p\", \"7-812j\"", "\"a\",W/\"7-812j\" ", "*"}) {
    request.set(http::field::if_none_match, value);
    EXPECT_TRUE(etagMatches(request, etag)) << value;
  }
  for (const std::string value : {"\"7-812p\"", "7-812j", "\"7-812j", "", "\"7-812\", j\""}) {
    request.set(http::field::if_none_match, value);
    EXPECT_FALSE(etagMatches(request, etag)) << value;
  }
  // Repeated fields form one list (RFC 9110 §5.3).
  request.set(http::field::if_none_match, "\"other\"");
  request.insert(http::field::if_none_match, etag);
  EXPECT_TRUE(etagMatches(request, etag));
}

TEST(NotModified, HasTheETagAndNoBody) {
  net::Request request{http::verb::get, "/", 11};
  const net::Response response = notModified(request, "\"x\"");
  EXPECT_EQ(response.result_int(), 304u);
  EXPECT_EQ(response[http::field::etag], "\"x\"");
  EXPECT_EQ(response[http::field::cache_control], "no-cache");
  EXPECT_TRUE(response.body().empty());
}

}  // namespace
}  // namespace rmap::app
