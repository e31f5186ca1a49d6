// Round trip of one CAN frame through the TCP transports on loopback, against a plain TCP echo of a
// line of the same size measured in the same run (same thread, same sockets API).
//
// Path measured: client Bus -> TCP -> server (socketcand server or CAN@net gateway emulator) ->
// virtual bus -> echo node -> back the same way. The baseline is a client writing a 40-byte line
// to a TCP echo server and reading it back. ratio = median CAN round trip / median TCP echo.
#include "axon/can/cannet_client.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/socketcand_client.hpp"
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/write.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <string>
#include <vector>

namespace asio = boost::asio;
using asio::ip::tcp;
using namespace axon;
using namespace std::chrono_literals;

namespace {

struct Samples {
  std::vector<double> us;
  double pct(double p) const {
    auto v = us;
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
  }
};

asio::awaitable<void> echo_node(can::Bus& bus) {
  for (;;) {
    auto f = co_await bus.receive();
    if (!f) co_return;
    (void)co_await bus.send(can::Frame::standard(f.value().id() + 1, f.value().payload()).value());
  }
}

asio::awaitable<Samples> can_round_trips(can::Bus& bus, int n) {
  Samples s;
  for (int i = 0; i < n; ++i) {
    const std::array<std::uint8_t, 8> d{1, 2, 3, 4, 5, 6, 7, static_cast<std::uint8_t>(i)};
    const auto t0 = std::chrono::steady_clock::now();
    if (!co_await bus.send(can::Frame::standard(0x100, d).value())) std::abort();
    auto r = co_await bus.receive(2s);
    if (!r || r.value().id() != 0x101) {
      fmt::print(stderr, "can_tcp: reply lost on {}\n", bus.name());
      std::exit(1);
    }
    s.us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  co_return s;
}

asio::awaitable<void> tcp_echo_server(tcp::acceptor& acc) {
  tcp::socket sock = co_await acc.async_accept(asio::use_awaitable);
  sock.set_option(tcp::no_delay(true));
  std::array<char, 4096> buf{};
  for (;;) {
    boost::system::error_code ec;
    const std::size_t n = co_await sock.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
    if (ec) co_return;
    co_await asio::async_write(sock, asio::buffer(buf.data(), n), asio::use_awaitable);
  }
}

asio::awaitable<Samples> tcp_round_trips(tcp::endpoint ep, int n) {
  tcp::socket sock(co_await asio::this_coro::executor);
  co_await sock.async_connect(ep, asio::use_awaitable);
  sock.set_option(tcp::no_delay(true));
  const std::string line = "< send 100 8 1 2 3 4 5 6 7 8 >\n";  // the size of a frame on the wire
  std::string in;
  Samples s;
  for (int i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    co_await asio::async_write(sock, asio::buffer(line), asio::use_awaitable);
    in.clear();
    co_await asio::async_read_until(sock, asio::dynamic_buffer(in), '\n', asio::use_awaitable);
    s.us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  co_return s;
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 5000;
  asio::io_context io;
  auto ex = io.get_executor();
  Samples base, scd, cn;
  asio::co_spawn(
      io,
      [&]() -> asio::awaitable<void> {
        // Baseline: plain TCP echo.
        tcp::acceptor acc(ex, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
        asio::co_spawn(ex, tcp_echo_server(acc), asio::detached);
        base = co_await tcp_round_trips(acc.local_endpoint(), n);

        can::VirtualBusRegistry reg(ex);
        (void)reg.add("vcan0").value();
        auto node = reg.open("vcan0").value();
        asio::co_spawn(ex, echo_node(*node), asio::detached);
        const net::Endpoint lo{"127.0.0.1", 0};
        auto server = can::SocketcandServer::create(ex, reg, lo).value();
        can::CanNetEmulatorOptions eo;
        eo.port = 0;
        auto gw = std::make_unique<can::CanNetGatewayEmulator>(ex, reg, std::vector<std::string>{"vcan0"}, eo);
        gw->start().value();

        // Arguments of co_awaited calls are named: gcc 12 mishandles temporaries built inside co_await.
        const net::Endpoint scd_ep = server->local_endpoint(), gw_ep = gw->local_endpoint();
        const std::string channel = "vcan0";
        const can::BusOptions bo;
        auto sb = (co_await can::SocketcandBus::connect(ex, scd_ep, channel, bo, 2s)).value();
        scd = co_await can_round_trips(*sb, n);
        const can::CanNetOptions co;
        std::vector<int> chans{1};
        auto gateway = (co_await can::CanNetGateway::connect(ex, gw_ep, std::move(chans), co)).value();
        auto cb = gateway->bus(1).value();
        cn = co_await can_round_trips(*cb, n);

        sb->close();
        cb->close();
        node->close();
        server->stop();
        gw->stop();
        io.stop();
      },
      asio::detached);
  io.run();

  const double b50 = base.pct(0.5), s50 = scd.pct(0.5), c50 = cn.pct(0.5);
  fmt::print("round trips: {} each, one thread, loopback TCP\n", n);
  fmt::print("  {:<30} median {:>7.1f} us  p99 {:>7.1f} us\n", "TCP echo (baseline)", b50, base.pct(0.99));
  fmt::print("  {:<30} median {:>7.1f} us  p99 {:>7.1f} us  ratio {:.2f}\n", "socketcand + virtual bus", s50, scd.pct(0.99), s50 / b50);
  fmt::print("  {:<30} median {:>7.1f} us  p99 {:>7.1f} us  ratio {:.2f}\n", "CAN@net + virtual bus", c50, cn.pct(0.99), c50 / b50);
  fmt::print("BENCH can_tcp n={} tcp_echo_us={:.1f} socketcand_us={:.1f} cannet_us={:.1f} socketcand_ratio={:.2f} "
             "cannet_ratio={:.2f} ratio={:.2f}\n",
             n, b50, s50, c50, s50 / b50, c50 / b50, std::max(s50, c50) / b50);
  return 0;
}
