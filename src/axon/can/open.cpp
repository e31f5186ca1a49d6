#include "axon/can/open.hpp"

#include "axon/can/cannet_client.hpp"
#include "axon/can/socketcan_bus.hpp"
#include "axon/can/socketcand_client.hpp"

#include <fmt/format.h>

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>

#include <algorithm>

namespace axon::can {

namespace {

CanNetOptions cannet_options(const OpenOptions& options) {
  CanNetOptions o;
  o.connect_timeout = options.connect_timeout;
  o.bitrate_kbit = options.bus.bitrate / 1000;
  o.bus_options = options.bus;
  return o;
}

bool same_endpoint(const net::Endpoint& a, const net::Endpoint& b) { return a.host == b.host && a.port == b.port; }

// The IPv4 address a host name stands for ("localhost" -> "127.0.0.1"), so that two names of one
// gateway share its single connection (a second one would take it over). A name that does not
// resolve stays as written: connecting then reports it.
std::string canonical_host(const std::string& host) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0 || found == nullptr) return host;
  char text[INET_ADDRSTRLEN] = {};
  const auto* in = reinterpret_cast<const sockaddr_in*>(found->ai_addr);
  const bool ok = ::inet_ntop(AF_INET, &in->sin_addr, text, sizeof text) != nullptr;
  ::freeaddrinfo(found);
  return ok ? std::string(text) : host;
}

bool same_bus(const BusSpec& a, const BusSpec& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case BusSpec::Kind::cannet: return same_endpoint(a.endpoint, b.endpoint) && a.cannet_channel == b.cannet_channel;
    case BusSpec::Kind::socketcand: return same_endpoint(a.endpoint, b.endpoint) && a.channel == b.channel;
    default: return a.channel == b.channel;
  }
}

}  // namespace

asio::awaitable<Result<std::unique_ptr<Bus>>> open_bus(asio::any_io_executor ex, const BusSpec& spec,
                                                       OpenOptions options) {
  using Kind = BusSpec::Kind;
  switch (spec.kind) {
    case Kind::virtual_bus: {
      if (!options.local)
        co_return Error(CanErrc::bad_spec,
                        fmt::format("'{}': virtual buses live inside one axon process; reach one from another process "
                                    "with socketcand://HOST:PORT/{} served by `axon can bridge`",
                                    spec.text, spec.channel));
      co_return options.local->open(spec.channel, options.bus);
    }
    case Kind::socketcand: {
      // Named arguments: gcc 12 mishandles temporaries built inside a co_await expression.
      const net::Endpoint endpoint = spec.endpoint;
      const std::string channel = spec.channel;
      auto r = co_await SocketcandBus::connect(ex, endpoint, channel, options.bus, options.connect_timeout);
      if (!r) co_return r.error();
      co_return std::unique_ptr<Bus>(std::move(r).value());
    }
    case Kind::cannet: {
      const CanNetOptions o = cannet_options(options);
      const net::Endpoint endpoint = spec.endpoint;
      std::vector<int> channels{spec.cannet_channel};
      auto gw = co_await CanNetGateway::connect(ex, endpoint, std::move(channels), o);
      if (!gw) co_return gw.error();
      co_return gw.value()->bus(spec.cannet_channel);
    }
    case Kind::socketcan: {
      auto r = SocketCanBus::open(ex, spec.channel, options.bus);
      if (!r) co_return r.error();
      co_return std::unique_ptr<Bus>(std::move(r).value());
    }
  }
  co_return Error(CanErrc::bad_spec, spec.text);
}

Result<void> check_distinct(const std::vector<BusSpec>& specs) {
  for (std::size_t i = 0; i < specs.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (same_bus(specs[i], specs[j]))
        return Error(CanErrc::bad_spec, fmt::format("'{}' is the same bus as '{}' (listed twice)", specs[i].text, specs[j].text));
  return ok();
}

asio::awaitable<Result<std::vector<std::unique_ptr<Bus>>>> open_buses(asio::any_io_executor ex,
                                                                      std::vector<BusSpec> specs, OpenOptions options) {
  for (auto& s : specs)
    if (s.kind == BusSpec::Kind::cannet || s.kind == BusSpec::Kind::socketcand) s.endpoint.host = canonical_host(s.endpoint.host);
  AXON_CO_TRY(check_distinct(specs));
  // One connection per gateway, with every channel asked of it.
  std::vector<std::pair<net::Endpoint, std::vector<int>>> gateways;
  for (const auto& s : specs) {
    if (s.kind != BusSpec::Kind::cannet) continue;
    auto it = std::find_if(gateways.begin(), gateways.end(), [&](const auto& g) { return same_endpoint(g.first, s.endpoint); });
    if (it == gateways.end()) it = gateways.insert(gateways.end(), {s.endpoint, {}});
    it->second.push_back(s.cannet_channel);
  }
  std::vector<std::shared_ptr<CanNetGateway>> connected;
  std::vector<std::unique_ptr<Bus>> out;
  auto fail = [&](const BusSpec& spec, const Error& e) {
    for (auto& b : out) b->close();
    for (auto& g : connected) g->close();
    if (e.detail.find(spec.text) != std::string::npos) return e;  // already named
    return Error(e.code, fmt::format("{}: {}", spec.text, e.detail));
  };
  const CanNetOptions cn = cannet_options(options);
  for (const auto& g : gateways) {
    const net::Endpoint ep = g.first;
    std::vector<int> chans = g.second;
    auto gw = co_await CanNetGateway::connect(ex, ep, std::move(chans), cn);
    if (!gw) {
      const auto& spec = *std::find_if(specs.begin(), specs.end(), [&](const BusSpec& s) { return s.kind == BusSpec::Kind::cannet && same_endpoint(s.endpoint, ep); });
      co_return fail(spec, gw.error());
    }
    connected.push_back(std::move(gw).value());
  }
  for (const auto& s : specs) {
    Result<std::unique_ptr<Bus>> bus = Error(CanErrc::bad_spec, s.text);
    if (s.kind == BusSpec::Kind::cannet) {
      auto it = std::find_if(connected.begin(), connected.end(), [&](const auto& g) { return same_endpoint(g->endpoint(), s.endpoint); });
      bus = (*it)->bus(s.cannet_channel);
    } else {
      const BusSpec spec = s;
      bus = co_await open_bus(ex, spec, options);
    }
    if (!bus) co_return fail(s, bus.error());
    out.push_back(std::move(bus).value());
  }
  co_return out;
}

}  // namespace axon::can
