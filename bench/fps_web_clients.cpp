// Does a watched focal plane upload slower? The fps_upload workload (500 robots, 20 points per arm,
// through 6 emulated CAN@net gateways at 1 Mbit/s with the wire model, bench/fps_rig.hpp) with the
// plane's live page served as `axon sim fps --http` serves it (web::FpsSimView read and published
// on the simulator's thread 10 times a second, the web server on a thread of its own), measured
// alternately with nobody watching and with 50 WebSocket clients connected to /ws?source=fps and
// reading every message (Beast clients on a fourth thread, as 50 browsers would).
//
// ratio_without / ratio_with: the uploads' achieved time over the busiest bus's wire time (a round is
// 10 uploads of every robot one after the other, about 2 s), best of 3 rounds each; ratio = with / without (1.0: the watchers cost the CAN work nothing). Also: the
// messages and bytes the clients received per second, and the clients the server dropped as too
// slow (web::ServerOptions::max_queued_messages).
#include "fps_rig.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/web/fps_sim_view.hpp"
#include "axon/web/server.hpp"

#include <boost/asio/detached.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <list>

using namespace axon;
namespace beast = boost::beast;
namespace ws = boost::beast::websocket;
using tcp = boost::asio::ip::tcp;

namespace {

constexpr std::size_t kClients = 50;
constexpr int kUploadsPerRound = 10;  // about 2 s of CAN work: 20 page updates reach every client
constexpr auto kPublishPeriod = std::chrono::milliseconds(100);

fps::protocol::Trajectory twenty_points() {
  std::vector<fps::protocol::ArmPoint> a, b;
  for (int i = 1; i <= 20; ++i) {
    a.push_back({1.5 * i, 0.5 * i});
    b.push_back({180.0 - 1.0 * i, 0.5 * i});
  }
  return fps::protocol::Trajectory::from_physical(a, b).value();
}

// What the clients received, all together.
struct Received {
  std::atomic<std::uint64_t> messages{0}, bytes{0}, connected{0}, closed{0};
};

// One watcher: connects, then reads messages until the stream ends.
bench::asio::awaitable<void> watch(std::uint16_t port, Received& got) {
  ws::stream<beast::tcp_stream> s(co_await bench::asio::this_coro::executor);
  co_await beast::get_lowest_layer(s).async_connect(tcp::endpoint(bench::asio::ip::make_address("127.0.0.1"), port),
                                                     bench::asio::use_awaitable);
  beast::get_lowest_layer(s).expires_never();
  co_await s.async_handshake("127.0.0.1", "/ws?source=fps", bench::asio::use_awaitable);
  ++got.connected;
  beast::flat_buffer buffer;
  for (;;) {
    boost::system::error_code ec;
    const auto n = co_await s.async_read(buffer, bench::asio::redirect_error(bench::asio::use_awaitable, ec));
    if (ec) break;
    ++got.messages;
    got.bytes += n;
    buffer.consume(buffer.size());
  }
  ++got.closed;
}

// The plane's page published on the simulator's thread until *alive is false.
bench::asio::awaitable<void> publish(web::FpsSimView& view, web::Source& source, std::shared_ptr<std::atomic<bool>> alive) {
  bench::asio::steady_timer timer(co_await bench::asio::this_coro::executor);
  while (*alive) {
    view.publish(source);
    timer.expires_after(kPublishPeriod);
    boost::system::error_code ec;
    co_await timer.async_wait(bench::asio::redirect_error(bench::asio::use_awaitable, ec));
  }
}

// The watchers' event loop on a thread of its own; connect() starts kClients of them, disconnect()
// ends them all (the loop and its sockets go).
struct Watchers {
  std::uint16_t port;
  Received got;
  std::unique_ptr<bench::asio::io_context> io;
  std::thread thread;

  void connect() {
    io = std::make_unique<bench::asio::io_context>();
    for (std::size_t i = 0; i < kClients; ++i)
      bench::asio::co_spawn(*io, watch(port, got), [](std::exception_ptr e) {
        if (e) std::fprintf(stderr, "a watcher failed to connect\n");
      });
    thread = std::thread([this] { io->run(); });
    while (got.connected < kClients && got.closed == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  void disconnect() {
    if (!io) return;
    io->stop();
    thread.join();
    io.reset();  // closes the sockets: the server sees them go
    got.connected = 0;
    got.closed = 0;
  }
};

}  // namespace

int main() {
  bench::FpsRig rig;
  rig.start();
  web::Server server;  // 127.0.0.1, any port, its own thread
  auto source = std::make_shared<web::Source>("fps", "fps: simulated focal plane", "fps");
  auto alive = std::make_shared<std::atomic<bool>>(true);
  auto view = rig.in_sim([&] { return std::make_unique<web::FpsSimView>(rig.plane, *rig.sim); });
  source->set_info(view->info_json());
  server.add(source);
  bench::asio::co_spawn(rig.sim_io, publish(*view, *source, alive), bench::asio::detached);

  const auto traj = twenty_points();
  auto& array = rig.fpa->array();
  const auto ids = array.ids();
  std::size_t failures = 0;
  Watchers watchers{server.port(), {}, nullptr, {}};
  double best[2] = {0, 0};
  for (int round = 0; round < 6; ++round) {
    const bool watched = round % 2 == 1;
    if (watched) watchers.connect();
    const auto m0 = watchers.got.messages.load(), b0 = watchers.got.bytes.load();
    const auto r = rig.measure([&] {
      for (int k = 0; k < kUploadsPerRound; ++k)
        rig.run([&]() -> bench::asio::awaitable<void> {
          co_await fps::host::for_each_concurrently(ids.size(), [&](std::size_t i) -> bench::asio::awaitable<void> {
            auto u = co_await array.find(ids[i])->upload_trajectory(traj);
            if (!u.ok() && failures++ < 5) std::fprintf(stderr, "robot %u: %s\n", unsigned{ids[i]}, u.describe().c_str());
          });
        });
    });
    const double messages = static_cast<double>(watchers.got.messages - m0), bytes = static_cast<double>(watchers.got.bytes - b0);
    std::printf("round %d, %s: %.3f s, busiest bus %.4f s wire (ratio %.2f)", round,
                watched ? "50 clients watching" : "nobody watching", r.achieved_s, r.floor_s, r.ratio());
    if (watched)
      std::printf("; clients got %.0f messages/s (%.1f per client per s), %.1f MB/s", messages / r.achieved_s,
                  messages / r.achieved_s / kClients, bytes / r.achieved_s / 1e6);
    std::printf("\n");
    auto& b = best[watched ? 1 : 0];
    if (b == 0 || r.ratio() < b) b = r.ratio();
    if (watched) watchers.disconnect();
  }
  const auto stats = server.stats();
  *alive = false;
  rig.in_sim([&] {
    view.reset();
    return 0;
  });
  server.stop();
  rig.stop();
  std::printf("server: %llu WebSocket clients accepted, %llu dropped as too slow, %llu messages, %.1f MB sent\n",
              static_cast<unsigned long long>(stats.ws_accepted), static_cast<unsigned long long>(stats.ws_dropped_slow),
              static_cast<unsigned long long>(stats.ws_messages), static_cast<double>(stats.ws_bytes) / 1e6);
  std::printf("BENCH fps_web_clients robots=%zu clients=%zu failures=%zu ratio_without=%.3f ratio_with=%.3f dropped=%llu ratio=%.3f\n",
              ids.size(), kClients, failures, best[0], best[1], static_cast<unsigned long long>(stats.ws_dropped_slow),
              best[1] / best[0]);
  return failures == 0 ? 0 : 1;
}
