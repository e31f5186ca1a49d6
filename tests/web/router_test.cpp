#include "axon/core/error.hpp"
#include "axon/web/router.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace axon::web {
namespace {

namespace fs = std::filesystem;

// A router over a temporary assets folder with one page and a file outside the folder.
class RouterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / fs::path("axon_web_router_" + std::to_string(::getpid()));
    fs::create_directories(root_ / "assets" / "js");
    std::ofstream(root_ / "assets" / "fps.html") << "<html>fps</html>";
    std::ofstream(root_ / "assets" / "js" / "fps.js") << "let x = 1;";
    std::ofstream(root_ / "assets" / ".hidden") << "secret";
    std::ofstream(root_ / "outside.txt") << "outside";
    fs::create_directories(root_ / "javascript" / "chart.js");
    std::ofstream(root_ / "javascript" / "chart.js" / "chart.min.js") << "/* chart */";
    router_ = std::make_unique<Router>((root_ / "assets").string(), (root_ / "javascript").string());
    source_ = std::make_shared<Source>("fps", "fps: a <test> plane", "fps");
    router_->add(source_);
  }
  void TearDown() override { fs::remove_all(root_); }

  HttpResponse get(std::string_view target) { return router_->handle({"GET", target}, stats_); }

  fs::path root_;
  std::unique_ptr<Router> router_;
  std::shared_ptr<Source> source_;
  ServerStats stats_;
};

TEST_F(RouterTest, IndexListsEverySourceWithItsPageAndTheEndpoints) {
  router_->add(std::make_shared<Source>("blmc", "blmc: board 1"));  // no page
  const auto r = get("/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.content_type, "text/html; charset=utf-8");
  EXPECT_NE(r.body.find("<a href=\"/fps.html\">fps: a &lt;test&gt; plane</a>"), std::string::npos) << r.body;
  EXPECT_NE(r.body.find("blmc: board 1 (blmc)"), std::string::npos) << r.body;
  for (const char* endpoint : {"/api/state", "/metrics", "/ws"}) EXPECT_NE(r.body.find(endpoint), std::string::npos) << endpoint;
}

TEST_F(RouterTest, StateIsNullUntilPublishedThenTheLatestObject) {
  EXPECT_EQ(get("/api/state").body, "{\"fps\":null}");
  source_->publish("{\"n\":1}");
  source_->publish("{\"n\":2}");
  const auto all = get("/api/state");
  EXPECT_EQ(all.content_type, "application/json");
  EXPECT_EQ(all.body, "{\"fps\":{\"n\":2}}");
  EXPECT_EQ(get("/api/fps/state?x=1").body, "{\"n\":2}");
  EXPECT_EQ(source_->latest()->sequence, 2u);
}

TEST_F(RouterTest, InfoAndSourcesAreJson) {
  source_->set_info("{\"layout\":\"default\"}");
  EXPECT_EQ(get("/api/fps/info").body, "{\"layout\":\"default\"}");
  EXPECT_EQ(get("/api/sources").body, "[{\"name\":\"fps\",\"title\":\"fps: a <test> plane\",\"page\":\"fps\"}]");
}

TEST_F(RouterTest, UnknownSourcesAndEndpointsAre404) {
  EXPECT_EQ(get("/api/blmc/state").status, 404);
  EXPECT_EQ(get("/api/fps/other").status, 404);
  EXPECT_EQ(get("/api/fps").status, 404);
  EXPECT_EQ(get("/api").status, 404);
}

TEST_F(RouterTest, ServesPageFilesWithTheirContentType) {
  const auto page = get("/fps.html");
  EXPECT_EQ(page.status, 200);
  EXPECT_EQ(page.body, "<html>fps</html>");
  EXPECT_EQ(page.content_type, "text/html; charset=utf-8");
  const auto js = get("/js/fps.js?v=2");
  EXPECT_EQ(js.body, "let x = 1;");
  EXPECT_EQ(js.content_type, "text/javascript; charset=utf-8");
}

TEST_F(RouterTest, NeverReadsOutsideTheAssetsFolder) {
  for (const char* target : {"/../outside.txt", "/js/../../outside.txt", "/.hidden", "//outside.txt", "/js/",
                             "/js//fps.js", "/%2e%2e/outside.txt", "/fps.html\\..\\x", "/missing.html"}) {
    const auto r = get(target);
    EXPECT_EQ(r.status, 404) << target;
    EXPECT_EQ(r.body.find("outside"), std::string::npos) << target;
    EXPECT_EQ(r.body.find("secret"), std::string::npos) << target;
  }
}

TEST_F(RouterTest, ServesScriptLibrariesFromTheJavascriptFolderOnly) {
  const auto r = get("/javascript/chart.js/chart.min.js");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "/* chart */");
  EXPECT_EQ(r.content_type, "text/javascript; charset=utf-8");
  EXPECT_EQ(get("/chart.js/chart.min.js").status, 404);  // not an asset
  for (const char* target : {"/javascript/../outside.txt", "/javascript/../assets/fps.html", "/javascript/", "/javascript/x.js"})
    EXPECT_EQ(get(target).status, 404) << target;
}

TEST_F(RouterTest, OnlyGetIsServedAndWsWantsAnUpgrade) {
  EXPECT_EQ(router_->handle({"POST", "/api/state"}, stats_).status, 405);
  EXPECT_EQ(router_->handle({"DELETE", "/"}, stats_).status, 405);
  EXPECT_EQ(get("/ws").status, 426);
}

TEST_F(RouterTest, MetricsStartWithTheServerCountersThenTheSources) {
  stats_.requests = 7;
  stats_.ws_dropped_slow = 2;
  source_->publish_metrics("# HELP axon_fps_x_total X\n# TYPE axon_fps_x_total counter\naxon_fps_x_total 5\n");
  const auto r = get("/metrics");
  EXPECT_EQ(r.content_type, "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_NE(r.body.find("\naxon_web_http_requests_total 7\n"), std::string::npos) << r.body;
  EXPECT_NE(r.body.find("\naxon_web_websocket_dropped_total 2\n"), std::string::npos) << r.body;
  EXPECT_TRUE(r.body.ends_with("axon_fps_x_total 5\n")) << r.body;
}

TEST_F(RouterTest, ASourceNameIsUniqueAndUrlSafe) {
  EXPECT_THROW(router_->add(std::make_shared<Source>("fps", "again")), Exception);
  EXPECT_THROW(Source("Fps/1", "bad"), Exception);
  EXPECT_THROW(Source("", "empty"), Exception);
}

TEST(RouterTarget, PathAndQueryParameters) {
  EXPECT_EQ(target_path("/ws?source=fps"), "/ws");
  EXPECT_EQ(target_path("/a#frag"), "/a");
  EXPECT_EQ(query_param("/ws?source=fps", "source"), "fps");
  EXPECT_EQ(query_param("/ws?x=1&source=blmc#f", "source"), "blmc");
  EXPECT_EQ(query_param("/ws?sources=1", "source"), "");
  EXPECT_EQ(query_param("/ws", "source"), "");
}

TEST(RouterTarget, WebSocketMessageNamesItsSourceAndSequence) {
  Source s("fps", "t");
  s.publish("{\"a\":1}");
  EXPECT_EQ(ws_message(s, *s.latest()), "{\"source\":\"fps\",\"seq\":1,\"state\":{\"a\":1}}");
}

}  // namespace
}  // namespace axon::web
