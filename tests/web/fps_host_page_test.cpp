// web::FpsClientPage (the fps actor's --http) over a blocking fps::Client on an in-process
// simulated plane, read over real HTTP on loopback: the robots show ready, the page goes quiet while
// the client does exclusive work and reads again after it, a move shows at its targets.
#include "http_client.hpp"

#include "axon/fps/host/client.hpp"
#include "axon/fps/sim/simulated_plane.hpp"
#include "axon/web/fps_host_page.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <thread>

namespace axon::web {
namespace {

using json = nlohmann::json;

struct PageRig {
  PageRig() {
    client.open(plane.plane());
    client.discover();
    page = std::make_unique<FpsClientPage>(FpsHostPageOptions{}, client);
    const auto where = page->where();
    port = static_cast<std::uint16_t>(std::stoi(where.substr(where.rfind(':') + 1)));
  }
  static fps::sim::SimulatedPlaneOptions fast() {
    fps::sim::SimulatedPlaneOptions o;
    o.time_scale = 20;
    o.plc = false;
    return o;
  }
  static fps::ClientConfig config() {
    fps::ClientConfig c;
    c.poll_interval_s = 0.02;
    c.discover_window_s = 0.3;
    return c;
  }
  json state() const { return json::parse(testing::body_of(testing::http_get(port, "/api/fps/state"))); }
  // The state once `ok` says yes (polled every 50 ms for up to `seconds`), else the last one.
  json wait_for(const std::function<bool(const json&)>& ok, double seconds = 10) const {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    json s = state();
    while (!ok(s) && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      s = state();
    }
    return s;
  }

  fps::sim::SimulatedPlane plane{"benchtop", fast()};
  fps::Client client{config()};
  std::unique_ptr<FpsClientPage> page;
  std::uint16_t port = 0;
};

// The longest time since the view's own last reply from any robot (null: never heard).
double oldest_reply_s(const json& s) {
  double oldest = 0;
  for (const auto& r : s["robots"]) oldest = std::max(oldest, r["ago"].is_null() ? 1e9 : r["ago"].get<double>());
  return oldest;
}

bool all_ready(const json& s) { return s.contains("states") && s["states"]["ready"] == 6; }

TEST(FpsClientPage, ShowsEveryRobotReadyReadBesideTheClient) {
  PageRig rig;
  const auto s = rig.wait_for([](const json& j) { return all_ready(j) && oldest_reply_s(j) < 1.0; });
  EXPECT_TRUE(all_ready(s)) << s.dump();
  EXPECT_LT(oldest_reply_s(s), 1.0) << s.dump();
  EXPECT_FALSE(s["lock"]["locked"].get<bool>());
}

TEST(FpsClientPage, ReadsNothingWhileTheClientWorksExclusivelyAndReadsAgainAfter) {
  PageRig rig;
  ASSERT_TRUE(all_ready(rig.wait_for([](const json& j) { return all_ready(j) && oldest_reply_s(j) < 1.0; })));
  rig.page->bus_use(fps::BusUse::exclusive);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // six read periods
  const auto quiet = rig.wait_for([](const json& j) { return oldest_reply_s(j) >= 1.4; }, 1);
  for (const auto& r : quiet["robots"]) EXPECT_GE(r["ago"].get<double>(), 1.4) << "robot " << r["id"] << " was read";
  rig.page->bus_use(fps::BusUse::shared);
  const auto again = rig.wait_for([](const json& j) { return oldest_reply_s(j) < 0.6; });
  EXPECT_LT(oldest_reply_s(again), 0.6) << again.dump();
}

TEST(FpsClientPage, AMoveBesideThePageEndsShownAtItsTargets) {
  PageRig rig;
  rig.page->bus_use(fps::BusUse::moving);
  const auto out = rig.client.goto_absolute({{3, {30, 150}}, {4, {60, 170}}});
  rig.page->bus_use(fps::BusUse::shared);
  ASSERT_TRUE(out.completed) << out.summary;
  const auto at = [](const json& s, int id, double a, double b) {
    for (const auto& r : s["robots"])
      if (r["id"] == id && !r["a"].is_null())
        return std::abs(r["a"].get<double>() - a) < 0.1 && std::abs(r["b"].get<double>() - b) < 0.1;
    return false;
  };
  const auto s = rig.wait_for([&](const json& j) { return at(j, 3, 30, 150) && at(j, 4, 60, 170); });
  EXPECT_TRUE(at(s, 3, 30, 150) && at(s, 4, 60, 170)) << s.dump();
}

TEST(FpsClientPage, IsRefusedOverAClientOpenedFromBusNamesAlone) {
  fps::sim::SimulatedPlane plane{"benchtop", PageRig::fast()};
  fps::Client client{PageRig::config()};
  client.open(plane.bus_specs());
  try {
    FpsClientPage page(FpsHostPageOptions{}, client);
    FAIL() << "a page over bus names alone was opened";
  } catch (const Exception& e) {
    EXPECT_NE(std::string(e.what()).find("needs the plane's layout"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace axon::web
