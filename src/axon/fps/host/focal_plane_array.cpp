#include "axon/fps/host/focal_plane_array.hpp"

#include "axon/can/bus_spec.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/layout_sweep.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/this_coro.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <set>

namespace axon::fps::host {

FocalPlaneArray::FocalPlaneArray(const FocalPlane& plane, FocalPlaneArrayOptions options)
    : plane_(plane), options_(std::move(options)) {}

FocalPlaneArray::~FocalPlaneArray() { *alive_ = false; }

asio::awaitable<Result<std::unique_ptr<FocalPlaneArray>>> FocalPlaneArray::connect(asio::any_io_executor executor,
                                                                                   const FocalPlane& plane,
                                                                                   FocalPlaneArrayOptions options) {
  std::unique_ptr<FocalPlaneArray> self(new FocalPlaneArray(plane, std::move(options)));
  const auto by_bus = plane.by_bus();
  if (by_bus.empty()) co_return Error(HostErrc::invalid_argument, fmt::format("layout '{}' has no robots", plane.name()));

  // One link per gateway that carries robots, with the channels they use.
  std::map<std::uint16_t, std::vector<int>> channels;
  for (const auto& [ref, ids] : by_bus) channels[ref.gateway].push_back(ref.channel);
  for (const auto& [gw, chans] : channels) {
    GatewayLink link;
    link.id = gw;
    if (auto it = self->options_.addresses.find(gw); it != self->options_.addresses.end()) {
      link.endpoint = it->second;
    } else {
      const auto* site = plane.gateway(gw);
      auto ep = net::parse_endpoint(site != nullptr ? site->address : "", can::kCanNetPort);
      if (!ep) co_return Error(HostErrc::invalid_argument, fmt::format("gateway {}: {}", gw, ep.error().message()));
      link.endpoint = ep.value();
    }
    self->gateways_.push_back(std::move(link));
  }

  // Connect to all at once.
  std::vector<std::optional<Error>> failures(self->gateways_.size());
  FocalPlaneArray* s = self.get();
  co_await for_each_concurrently(self->gateways_.size(), [&, s](std::size_t i) -> asio::awaitable<void> {
    auto& link = s->gateways_[i];
    const net::Endpoint ep = link.endpoint;
    const std::vector<int> chans = channels[link.id];
    auto r = co_await can::CanNetGateway::connect(executor, ep, chans, s->options_.gateway);
    if (!r) {
      failures[i] = r.error();
      co_return;
    }
    link.gateway = std::move(r).value();
  });
  for (std::size_t i = 0; i < failures.size(); ++i) {
    if (!failures[i]) continue;
    for (auto& l : self->gateways_)
      if (l.gateway) l.gateway->close();
    co_return Error(failures[i]->code, fmt::format("gateway {} at {}: {}", self->gateways_[i].id,
                                                   self->gateways_[i].endpoint.to_string(), failures[i]->detail));
  }

  // Buses in layout order (by gateway, then channel).
  std::vector<can::Bus*> raw;
  for (const auto& [ref, ids] : by_bus) {
    for (auto& link : self->gateways_) {
      if (link.id != ref.gateway) continue;
      auto bus = link.gateway->bus(ref.channel);
      if (!bus) co_return Error(bus.error().code, fmt::format("gateway {} channel {}: {}", ref.gateway, int{ref.channel},
                                                              bus.error().detail));
      link.buses.push_back(self->refs_.size());
      self->refs_.push_back(ref);
      raw.push_back(bus.value().get());
      self->buses_.push_back(std::move(bus).value());
    }
  }
  self->array_ = std::make_unique<Array>(raw, self->options_.array);
  for (std::size_t i = 0; i < self->refs_.size(); ++i) {
    for (auto id : by_bus.at(self->refs_[i])) {
      const auto* site = plane.find(id);
      if (site != nullptr && site->offline) continue;
      auto added = self->array_->add(id, i);
      if (!added) co_return added.error();
    }
  }
  if (self->options_.plc) {
    self->plc_ = std::make_unique<plc::AsyncPlc>(*self->options_.plc, self->options_.plc_map, self->options_.plc_client);
  }
  asio::co_spawn(executor, watch(self.get(), self->alive_), asio::detached);
  co_return self;
}

std::optional<std::size_t> FocalPlaneArray::bus_index(const BusRef& ref) const {
  for (std::size_t i = 0; i < refs_.size(); ++i)
    if (refs_[i] == ref) return i;
  return std::nullopt;
}

asio::awaitable<void> FocalPlaneArray::watch(FocalPlaneArray* self, std::shared_ptr<bool> alive) {
  while (*alive) {
    co_await core::sleep_for(self->options_.connection_poll);
    if (!*alive || self->closed_) co_return;
    self->check_links();
  }
}

void FocalPlaneArray::check_links() {
  for (const auto& link : gateways_) {
    if (link.gateway->is_connected() || std::ranges::find(lost_, link.id) != lost_.end()) continue;
    link_lost(link);
  }
}

asio::awaitable<void> FocalPlaneArray::link_stops_done() {
  while (reconnecting_ > 0) co_await core::sleep_for(10ms);
}

void FocalPlaneArray::link_lost(const GatewayLink& link) {
  lost_.push_back(link.id);
  const auto reason = fmt::format("gateway {} at {} disconnected ({})", link.id, link.endpoint.to_string(),
                                  link.gateway->disconnect_reason().detail);
  spdlog::error("fps focal plane: {}: stopping every robot", reason);
  array_->request_stop(reason);
  std::vector<std::uint16_t> behind;
  std::size_t moving = 0;
  for (auto b : link.buses) {
    for (auto id : array_->ids_on(b)) {
      behind.push_back(id);
      moving += array_->moving().contains(id) ? 1 : 0;
    }
  }
  if (moving == 0) {
    link_stops_.push_back(fmt::format("gateway {}: lost; none of its {} robots was moving under this host", link.id,
                                      behind.size()));
    return;
  }
  if (!options_.reconnect_to_stop) {
    link_stops_.push_back(fmt::format("gateway {}: lost with {} robots moving behind it: NOT stopped (no reconnection "
                                      "allowed)", link.id, moving));
    return;
  }
  ++reconnecting_;
  asio::co_spawn(array_->client(0).bus().get_executor(), stop_behind(link, std::move(behind), moving),
                 [this](std::exception_ptr) { --reconnecting_; });
}

// One reconnection to a lost gateway, a TRAJECTORY_ABORT broadcast on each of its channels
// (acknowledgements collected briefly), and the connection closed again.
asio::awaitable<void> FocalPlaneArray::stop_behind(GatewayLink link, std::vector<std::uint16_t> robots, std::size_t moving) {
  const auto ex = co_await asio::this_coro::executor;
  std::vector<int> channels;
  for (auto b : link.buses) channels.push_back(refs_[b].channel);
  can::CanNetOptions o = options_.gateway;
  o.connect_timeout = options_.reconnect_timeout;
  o.reply_timeout = options_.reconnect_timeout;
  const net::Endpoint ep = link.endpoint;
  spdlog::warn("fps focal plane: gateway {}: {} robots were moving behind it; reconnecting once to stop them", link.id, moving);
  auto gw = co_await can::CanNetGateway::connect(ex, ep, channels, o);
  if (!gw) {
    link_stops_.push_back(fmt::format("gateway {}: {} robots were moving behind it: NOT stopped, the reconnection "
                                      "failed: {}", link.id, moving, gw.error().message()));
    spdlog::error("fps focal plane: {}", link_stops_.back());
    co_return;
  }
  std::size_t acked = 0;
  std::vector<std::string> failures;
  for (auto b : link.buses) {
    const int ch = refs_[b].channel;
    const auto ids = array_->ids_on(b);
    const std::set<std::uint16_t> expected(ids.begin(), ids.end());
    auto bus = gw.value()->bus(ch);
    if (!bus) {
      failures.push_back(bus.error().message());
      continue;
    }
    CommandClient client(*bus.value(), {}, array_->motion_lock());  // the array's lock, as on every bus
    BroadcastOptions bo;
    bo.expected_ids = expected;
    bo.window = options_.reconnect_window;
    auto r = co_await client.broadcast(protocol::CommandId::trajectory_abort, {}, bo);
    if (r) {
      for (const auto& reply : r.value().replies) acked += expected.contains(reply.positioner) ? 1 : 0;
    } else {
      failures.push_back(r.error().message());
    }
    co_await client.stop();
    bus.value()->close();
  }
  gw.value()->close();
  link_stops_.push_back(fmt::format("gateway {}: reconnected once and sent TRAJECTORY_ABORT on channel(s) {}: {} of {} "
                                    "robots acknowledged ({} had been moving){}{}",
                                    link.id, fmt::join(channels, ", "), acked, robots.size(), moving,
                                    failures.empty() ? "" : "; failed: ", fmt::join(failures, "; ")));
  spdlog::warn("fps focal plane: {}", link_stops_.back());
}

asio::awaitable<LayoutCheck> FocalPlaneArray::check_layout() {
  LayoutBuses buses;
  for (std::size_t i = 0; i < refs_.size(); ++i) buses.emplace_back(refs_[i], &array_->client(i));
  auto check = co_await check_layout_on_buses(plane_, buses, options_.check_window);
  co_return check;
}

asio::awaitable<Result<DiscoveryReport>> FocalPlaneArray::discover() {
  std::map<std::size_t, std::size_t> expected;
  for (std::size_t i = 0; i < refs_.size(); ++i) expected[i] = array_->ids_on(i).size();
  auto r = co_await array_->discover(expected);
  co_return r;
}

asio::awaitable<Result<TrajectoryReport>> FocalPlaneArray::run_trajectories(
    std::map<std::uint16_t, protocol::Trajectory> trajectories, TrajectoryOptions options, bool by_sync_line) {
  if (by_sync_line) {
    if (!plc_) co_return Error(HostErrc::invalid_argument, "start by the sync line needs the PLC (no PLC endpoint given)");
    plc::AsyncPlc* p = plc_.get();
    const core::Duration hold = options_.sync_hold;
    options.sync_line = [p, hold]() -> asio::awaitable<Result<void>> {
      auto r = co_await p->pulse_sync_line(hold);
      co_return r;
    };
  }
  auto r = co_await array_->run_trajectories(std::move(trajectories), std::move(options));
  // A gateway lost during the run (even one the watch has not polled yet): the stop of its robots
  // through a reconnection belongs to this run, so it ends before the caller reads link_stops().
  if (!closed_) check_links();
  co_await link_stops_done();
  co_return r;
}

asio::awaitable<void> FocalPlaneArray::close() {
  if (closed_) co_return;
  closed_ = true;
  *alive_ = false;
  co_await link_stops_done();
  co_await array_->close();
  for (auto& b : buses_) b->close();
  for (auto& l : gateways_)
    if (l.gateway) l.gateway->close();
  plc_.reset();
}

}  // namespace axon::fps::host
