// `axon demo`: runs what axon can do today against its embedded simulators and says what happened.
// It grows with every device family.
#include "axon/can/cannet_client.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/socketcand_client.hpp"
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"
#include "commands.hpp"
#include "demo_fps.hpp"
#include "demo_parts.hpp"
#include "run.hpp"

#include <boost/asio/detached.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <vector>

namespace axon::app {
namespace {

using namespace std::chrono_literals;
using can::Bus;
using can::Frame;

// A stand-in device on the virtual bus: answers every standard frame id N with id N+1 and the
// same data, like a node acknowledging commands.
asio::awaitable<void> echo_device(Bus& bus) {
  for (;;) {
    auto f = co_await bus.receive();
    if (!f) co_return;
    const Frame& in = f.value();
    if (in.is_extended() || in.is_remote() || in.id() >= can::Frame::kMaxStandardId) continue;
    (void)co_await bus.send(Frame::standard(in.id() + 1, in.payload()).value());
  }
}

struct RoundTrips {
  std::vector<double> us;
  std::uint64_t lost = 0;
  [[nodiscard]] double percentile(double p) const {
    if (us.empty()) return 0;
    auto v = us;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
  }
};

asio::awaitable<RoundTrips> round_trips(Bus& bus, int count) {
  RoundTrips r;
  for (int i = 0; i < count; ++i) {
    const std::array<std::uint8_t, 8> data{0xA5, static_cast<std::uint8_t>(i), 0, 1, 2, 3, 4, 5};
    const auto t0 = std::chrono::steady_clock::now();
    if (!co_await bus.send(Frame::standard(0x100, data).value())) {
      ++r.lost;
      continue;
    }
    bool got = false;
    while (!got) {
      auto reply = co_await bus.receive(1s);
      if (!reply) break;
      got = reply.value().id() == 0x101 && reply.value().payload()[1] == static_cast<std::uint8_t>(i);
    }
    if (!got) {
      ++r.lost;
      continue;
    }
    r.us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  co_return r;
}

void report(const char* path, const RoundTrips& r, int count) {
  fmt::print("  {:<34} {:>4}/{} answered, round trip median {:>7.1f} us, p99 {:>7.1f} us\n", path, r.us.size(), count,
             r.percentile(0.5), r.percentile(0.99));
}

int run_can_fps_blmc();

int run_demo() {
  const int rc = run_can_fps_blmc();
  if (rc != 0) return rc;
  return demo_c4g();
}

int run_can_fps_blmc() {
  return run_command([](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    auto ex = io.get_executor();
    const int n = 200;
    fmt::print("axon demo: the CAN foundation\n\n");

    can::VirtualBusRegistry registry(ex);
    can::WireModel wire{true, can::kDefaultBitrate, true};
    auto vbus = need(registry.add("vcan0", wire));
    fmt::print("1. virtual bus vcan0: 1 Mbit/s, exact bit timing, frames paced in real time\n");
    auto device = need(registry.open("vcan0"));
    asio::co_spawn(ex, echo_device(*device), asio::detached);
    fmt::print("   echo device attached: answers id N with id N+1, same data\n");
    const Frame sample = Frame::parse("100#A500010203040506").value();
    fmt::print("   a frame like {} takes {} bits = {} us on the wire\n\n", sample.to_string(), can::frame_bits(sample).total,
               can::frame_time(sample).count() / 1000);

    const net::Endpoint loopback{"127.0.0.1", 0};
    auto scd = need(can::SocketcandServer::create(ex, registry, loopback));
    can::CanNetEmulatorOptions eo;
    eo.port = 0;
    auto gw = std::make_unique<can::CanNetGatewayEmulator>(ex, registry, std::vector<std::string>{"vcan0"}, eo);
    need(gw->start());
    fmt::print("2. socketcand server on {} (python-can: interface='socketcand', channel='vcan0')\n",
               scd->local_endpoint().to_string());
    fmt::print("   CAN@net NT gateway emulator on {} (channel 1 = vcan0)\n\n", gw->local_endpoint().to_string());

    fmt::print("3. round trips host -> transport -> vcan0 -> echo device -> back ({} frames each)\n", n);
    auto direct = need(registry.open("vcan0"));
    report("in-process virtual bus", co_await round_trips(*direct, n), n);
    // Arguments of co_awaited calls are named: gcc 12 mishandles temporaries built inside co_await.
    const net::Endpoint scd_ep = scd->local_endpoint(), gw_ep = gw->local_endpoint();
    const std::string channel = "vcan0";
    const can::BusOptions bus_options;
    auto r1 = co_await can::SocketcandBus::connect(ex, scd_ep, channel, bus_options, 2s);
    auto scd_bus = need(std::move(r1));
    report("socketcand over TCP loopback", co_await round_trips(*scd_bus, n), n);
    const can::CanNetOptions cn;
    std::vector<int> gw_channels{1};
    auto r2 = co_await can::CanNetGateway::connect(ex, gw_ep, std::move(gw_channels), cn);
    auto gateway = need(std::move(r2));
    auto cn_bus = need(gateway->bus(1));
    report("CAN@net over TCP loopback", co_await round_trips(*cn_bus, n), n);

    const auto& vs = vbus->stats();
    const auto now = std::chrono::steady_clock::now();
    fmt::print("\n4. vcan0 carried {} frames, {} bits, busy {:.1f} ms: load {:.1f}% since start\n", vs.frames, vs.bits,
               std::chrono::duration<double, std::milli>(vs.busy).count(), 100.0 * vbus->load(now));
    fmt::print("   (each round trip puts two frames on the bus; the rest of the time goes to the transports)\n");

    scd_bus->close();
    cn_bus->close();
    direct->close();
    device->close();
    scd->stop();
    gw->stop();
    const asio::any_io_executor any_ex = ex;
    co_await demo_fps(any_ex, set_on_signal);
    set_on_signal([] {});  // the fps part's array is gone; a signal from here on is the blmc part's
    if (received_stop_signal().load() != 0) co_return exit_code_value::failed;  // run_command makes it 128+N
    const int blmc = co_await demo_blmc(any_ex, set_on_signal);
    co_return blmc;
  });
}

}  // namespace

void add_demo_command(CLI::App& app, GlobalOptions& global) {
  auto* cmd = app.add_subcommand("demo", "run what axon can do today against the embedded simulators");
  cmd->callback([&global] { global.exit_code = run_demo(); });
}

}  // namespace axon::app
