#include "axon/core/error.hpp"
#include "axon/web/server.hpp"
#include "http_client.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

namespace axon::web {
namespace {

using namespace std::chrono_literals;
using testing::body_of;
using testing::http_exchange;
using testing::http_get;

ServerOptions test_options() {
  ServerOptions o;
  o.assets_dir = std::filesystem::temp_directory_path().string();
  o.push_period = 10ms;
  return o;
}

// Polls `done` until it holds or 20 s passed (a bound for a hung test, not a timing requirement).
template <class F>
bool eventually(F done) {
  const auto until = std::chrono::steady_clock::now() + 20s;
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

TEST(WebServer, ListensOnAnyFreePortOfLoopbackByDefault) {
  Server server(test_options());
  EXPECT_EQ(server.address(), "127.0.0.1");
  EXPECT_NE(server.port(), 0);
  EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/");
}

TEST(WebServer, AnswersApiStateOverHttp) {
  Server server(test_options());
  auto source = std::make_shared<Source>("fps", "plane");
  server.add(source);
  source->publish("{\"robots\":[]}");
  const auto response = http_get(server.port(), "/api/state");
  EXPECT_TRUE(response.starts_with("HTTP/1.1 200 OK\r\n")) << response;
  EXPECT_NE(response.find("Content-Type: application/json"), std::string::npos) << response;
  EXPECT_EQ(body_of(response), "{\"fps\":{\"robots\":[]}}");
  EXPECT_EQ(server.stats().requests, 1u);
}

TEST(WebServer, KeepsAConnectionOpenForSeveralRequests) {
  Server server(test_options());
  const auto response = http_exchange(server.port(),
                                      "GET /api/sources HTTP/1.1\r\nHost: t\r\n\r\n"
                                      "GET /nothing HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n");
  EXPECT_TRUE(response.starts_with("HTTP/1.1 200 OK")) << response;
  EXPECT_NE(response.find("HTTP/1.1 404 Not Found"), std::string::npos) << response;
  const auto stats = server.stats();
  EXPECT_EQ(stats.requests, 2u);
  EXPECT_EQ(stats.not_found, 1u);
}

TEST(WebServer, MalformedRequestGets400AndIsCounted) {
  Server server(test_options());
  const auto response = http_exchange(server.port(), "GARBAGE\x01 / HTTP/9\r\n\r\n");
  EXPECT_TRUE(response.starts_with("HTTP/1.1 400 Bad Request")) << response;
  EXPECT_EQ(server.stats().bad_requests, 1u);
  // The server goes on serving.
  EXPECT_TRUE(http_get(server.port(), "/").starts_with("HTTP/1.1 200 OK"));
}

TEST(WebServer, OversizedRequestGets400) {
  ServerOptions o = test_options();
  o.max_request_bytes = 1024;
  Server server(o);
  const std::string huge = "GET / HTTP/1.1\r\nHost: t\r\nX-Pad: " + std::string(4096, 'x') + "\r\n\r\n";
  EXPECT_TRUE(http_exchange(server.port(), huge).starts_with("HTTP/1.1 400 Bad Request"));
  EXPECT_EQ(server.stats().bad_requests, 1u);
}

TEST(WebServer, RawRequestPathAnswersLikeTheServer) {
  Router router(std::filesystem::temp_directory_path().string());
  ServerStats stats;
  const auto ok = answer_raw_request(router, "GET /api/state HTTP/1.1\r\nHost: t\r\n\r\n", stats);
  EXPECT_TRUE(ok.starts_with("HTTP/1.1 200 OK")) << ok;
  EXPECT_TRUE(ok.ends_with("{}")) << ok;
  EXPECT_TRUE(answer_raw_request(router, "GET /api/state HTTP/1.1\r\nHost:", stats).starts_with("HTTP/1.1 400"));
  EXPECT_TRUE(answer_raw_request(router, "", stats).starts_with("HTTP/1.1 400"));
  EXPECT_TRUE(answer_raw_request(router, "POST / HTTP/1.1\r\nContent-Length: 3\r\n\r\nab", stats).starts_with("HTTP/1.1 400"));
  EXPECT_EQ(stats.requests, 4u);
  EXPECT_EQ(stats.bad_requests, 3u);
}

TEST(WebServer, InvalidAddressThrows) {
  ServerOptions o = test_options();
  o.address = "999.1.1.1";
  EXPECT_THROW(Server{o}, Exception);
}

// A WebSocket client that completes its handshake and then reads nothing: the server's writes
// back up in the socket buffers, its queue fills, and it is dropped instead of buffered.
TEST(WebServer, DropsAWebSocketClientThatDoesNotRead) {
  ServerOptions o = test_options();
  o.max_queued_messages = 2;
  Server server(o);
  auto source = std::make_shared<Source>("fps", "plane");
  server.add(source);
  testing::Socket slow(server.port(), 4096);
  slow.send(testing::kWebSocketUpgrade);
  ASSERT_TRUE(eventually([&] { return server.stats().ws_open == 1; }));
  const std::string big = "{\"pad\":\"" + std::string(1 << 20, 'x') + "\"}";  // 1 MB a message
  ASSERT_TRUE(eventually([&] {
    source->publish(big);  // a new state each time: the server has something new to send
    return server.stats().ws_dropped_slow == 1;
  }));
  EXPECT_TRUE(eventually([&] { return server.stats().ws_open == 0; }));
  const auto stats = server.stats();
  EXPECT_EQ(stats.ws_accepted, 1u);
  // What it took before the drop is bounded by the queue: nothing piles up on the server.
  EXPECT_LT(stats.ws_messages, 64u);
}

TEST(WebServer, StopsWithClientsConnected) {
  auto server = std::make_unique<Server>(test_options());
  testing::Socket idle(server->port());  // says nothing
  testing::Socket ws(server->port());
  ws.send(testing::kWebSocketUpgrade);
  ASSERT_TRUE(eventually([&] { return server->stats().ws_open == 1; }));
  server->stop();  // returns: every connection was closed
  EXPECT_EQ(server->stats().ws_accepted, 1u);
}

}  // namespace
}  // namespace axon::web
