#include "can/open.hpp"

#include "can/cannet_client.hpp"
#include "can/socketcan_bus.hpp"
#include "can/socketcand_client.hpp"

#include <fmt/format.h>

namespace axon::can {

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
      CanNetOptions o;
      o.connect_timeout = options.connect_timeout;
      o.bitrate_kbit = options.bus.bitrate / 1000;
      o.bus_options = options.bus;
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

}  // namespace axon::can
