#include "axon/fps/host/layout_sweep.hpp"

#include "axon/fps/host/concurrent.hpp"

namespace axon::fps {

boost::asio::awaitable<BusSweep> sweep_buses(LayoutBuses buses, core::Duration window) {
  BusSweep sweep;
  std::vector<Result<host::BroadcastResult>> results;
  for (std::size_t i = 0; i < buses.size(); ++i) results.emplace_back(Error(host::HostErrc::cancelled));
  co_await host::for_each_concurrently(buses.size(), [&](std::size_t i) -> boost::asio::awaitable<void> {
    host::BroadcastOptions options;
    options.window = window;
    protocol::Payload payload;
    auto r = co_await buses[i].second->broadcast(protocol::CommandId::get_id, payload, std::move(options));
    results[i] = std::move(r);
  });
  for (std::size_t i = 0; i < buses.size(); ++i) {
    const BusRef bus = buses[i].first;
    if (!results[i]) {
      sweep.failed[bus] = results[i].error().message();
      continue;
    }
    auto& ids = sweep.found[bus];
    // Any reply counts: a robot that refuses GET_ID (whatever the code) is still on this bus.
    for (const auto& reply : results[i].value().replies) ids.insert(reply.positioner);
  }
  co_return sweep;
}

boost::asio::awaitable<LayoutCheck> check_layout_on_buses(const FocalPlane& plane, LayoutBuses buses,
                                                          core::Duration window) {
  auto sweep = co_await sweep_buses(std::move(buses), window);
  co_return check_layout(plane, sweep);
}

}  // namespace axon::fps
