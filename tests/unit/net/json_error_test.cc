#include "net/json_error.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace rmap::net {
namespace {

namespace http = boost::beast::http;

TEST(JsonError, BuildsTheErrorShape) {
  const Response response = jsonError(http::status::not_found, "no_such_map", "map \"a\" not found", 11, true);
  EXPECT_EQ(response.result(), http::status::not_found);
  EXPECT_EQ(response.version(), 11u);
  EXPECT_TRUE(response.keep_alive());
  EXPECT_EQ(response[http::field::content_type], "application/json");
  EXPECT_EQ(response[http::field::content_length], std::to_string(response.body().size()));
  const auto body = nlohmann::json::parse(response.body());
  EXPECT_EQ(body, (nlohmann::json{{"error", {{"code", "no_such_map"}, {"message", "map \"a\" not found"}}}}));
}

TEST(JsonError, DefaultsToClosingHttp11) {
  const Response response = jsonError(http::status::bad_request, "bad_request", "x");
  EXPECT_EQ(response.version(), 11u);
  EXPECT_FALSE(response.keep_alive());
  EXPECT_EQ(response[http::field::connection], "close");
}

TEST(JsonError, FollowsHttp10) {
  const Response response = jsonError(http::status::forbidden, "forbidden", "x", 10, true);
  EXPECT_EQ(response.version(), 10u);
  EXPECT_TRUE(response.keep_alive());
}

TEST(JsonError, InvalidUtf8InTheMessageIsReplacedNotThrown) {
  const Response response = jsonError(http::status::bad_request, "bad_request", "bad byte \xff here");
  const auto body = nlohmann::json::parse(response.body());
  EXPECT_EQ(body["error"]["message"], "bad byte \xEF\xBF\xBD here");
}

}  // namespace
}  // namespace rmap::net
